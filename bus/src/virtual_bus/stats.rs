//! Bus-load statistics of the virtual bus.

use std::collections::BTreeMap;
use std::time::Duration;

use crate::CanId;

/// A snapshot of what happened on a virtual bus since it was created (or since the last
/// [`VirtualBus::reset_stats`](super::VirtualBus::reset_stats)).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BusStats {
    /// Frames delivered, per identifier (ordered, so snapshots are deterministic).
    pub frames_by_id: BTreeMap<CanId, u64>,
    /// Frames delivered in total (duplicates included).
    pub frames: u64,
    /// Bits that occupied the wire, delivered and corrupted frames alike (a CAN FD frame's
    /// bits at both its bit rates).
    pub bits: u64,
    /// Time the wire was busy.
    pub busy: Duration,
    /// Time covered by these statistics.
    pub elapsed: Duration,
    /// Busy time as a percentage of elapsed time (0 when no time has elapsed).
    pub load_percent: f64,
    /// Frames that failed on the wire (corruption faults).
    pub errors: u64,
    /// Frames removed before reaching the wire (drop and silence faults, bus-off flushes).
    pub dropped: u64,
    /// Sends rejected because the node's transmit queue was full.
    pub tx_queue_full: u64,
}

/// Running counters kept by the wire.
#[derive(Debug, Default)]
pub(super) struct StatsCounter {
    pub(super) since: Duration,
    pub(super) frames_by_id: BTreeMap<CanId, u64>,
    pub(super) frames: u64,
    pub(super) bits: u64,
    pub(super) busy: Duration,
    pub(super) errors: u64,
    pub(super) dropped: u64,
    pub(super) tx_queue_full: u64,
}

impl StatsCounter {
    pub(super) fn snapshot(&self, now: Duration) -> BusStats {
        let elapsed = now.saturating_sub(self.since);
        let load_percent = if elapsed.is_zero() {
            0.0
        } else {
            100.0 * self.busy.as_secs_f64() / elapsed.as_secs_f64()
        };
        BusStats {
            frames_by_id: self.frames_by_id.clone(),
            frames: self.frames,
            bits: self.bits,
            busy: self.busy,
            elapsed,
            load_percent,
            errors: self.errors,
            dropped: self.dropped,
            tx_queue_full: self.tx_queue_full,
        }
    }
}
