//! Run-time fault injection on the virtual bus.
//!
//! Faults are evaluated when a frame wins arbitration, in the order they were injected, at the
//! frame's virtual start time, so a run with the same faults is as deterministic as one without.

use std::sync::Arc;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

use super::wire::Shared;
use crate::CanId;

/// Which frames a fault applies to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FrameFilter {
    /// Every frame.
    All,
    /// Frames with this identifier.
    Id(CanId),
    /// Frames sent by nodes attached under this name.
    Node(String),
}

impl FrameFilter {
    pub(super) fn matches(&self, id: CanId, node_name: &str) -> bool {
        match self {
            Self::All => true,
            Self::Id(wanted) => *wanted == id,
            Self::Node(name) => name == node_name,
        }
    }
}

/// What a fault does to a matching frame.
#[derive(Debug, Clone, PartialEq)]
pub enum FaultKind {
    /// The frame never reaches the wire: it takes no bus time and nobody (not even the tap)
    /// sees it. The sender is not told, as with a frame lost in a gateway. Counted in
    /// [`BusStats::dropped`](super::BusStats::dropped).
    Drop,
    /// Like [`FaultKind::Drop`], but each matching frame is dropped with this probability,
    /// decided by a random generator seeded with `seed` (same seed, same frames dropped).
    DropWithProbability {
        /// Probability in `0.0..=1.0` that a matching frame is dropped.
        probability: f64,
        /// Seed of the fault's own random generator.
        seed: u64,
    },
    /// The frame (and, keeping the sender's FIFO order, the frames queued behind it) waits this
    /// long before it may compete for the bus again; it keeps its place otherwise.
    Delay(Duration),
    /// The frame occupies the wire for its full length but fails its CRC: nobody receives it,
    /// the tap does not see it, and [`BusStats::errors`](super::BusStats::errors) counts it.
    /// No automatic retransmission is modelled.
    Corrupt,
    /// The frame is delivered twice, the copy directly after the original (as when the sender
    /// misses the acknowledgement and retransmits); both copies take bus time.
    Duplicate,
}

/// A fault to inject: what it does, which frames it hits, for how long and how often.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    /// The effect on a matching frame.
    pub kind: FaultKind,
    /// The frames it applies to.
    pub filter: FrameFilter,
    /// How long the fault stays active after injection; `None` until removed.
    pub duration: Option<Duration>,
    /// How many frames it affects at most before it retires; `None` for no limit.
    pub max_frames: Option<u64>,
}

impl Fault {
    /// A fault of `kind` on frames matching `filter`, active until removed.
    pub fn new(kind: FaultKind, filter: FrameFilter) -> Self {
        Self {
            kind,
            filter,
            duration: None,
            max_frames: None,
        }
    }

    /// Drop every matching frame.
    pub fn drop(filter: FrameFilter) -> Self {
        Self::new(FaultKind::Drop, filter)
    }

    /// Drop matching frames with `probability`, using a generator seeded with `seed`.
    pub fn drop_with_probability(filter: FrameFilter, probability: f64, seed: u64) -> Self {
        Self::new(FaultKind::DropWithProbability { probability, seed }, filter)
    }

    /// Hold matching frames back by `delay` before they compete for the bus.
    pub fn delay(filter: FrameFilter, delay: Duration) -> Self {
        Self::new(FaultKind::Delay(delay), filter)
    }

    /// Corrupt matching frames (bus time used, nobody receives them, errors counted).
    pub fn corrupt(filter: FrameFilter) -> Self {
        Self::new(FaultKind::Corrupt, filter)
    }

    /// Deliver matching frames twice.
    pub fn duplicate(filter: FrameFilter) -> Self {
        Self::new(FaultKind::Duplicate, filter)
    }

    /// Keep the fault active for `duration` of bus time after injection only.
    pub fn for_duration(mut self, duration: Duration) -> Self {
        self.duration = Some(duration);
        self
    }

    /// Retire the fault after it has affected `frames` frames.
    pub fn times(mut self, frames: u64) -> Self {
        self.max_frames = Some(frames);
        self
    }
}

/// Identifies an injected fault so it can be removed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct FaultId(pub(super) u64);

/// An injected fault with its bookkeeping.
pub(super) struct ActiveFault {
    pub(super) fault: Fault,
    /// Bus time (since creation) at which it was injected.
    pub(super) since: Duration,
    /// Frames it may still affect.
    pub(super) remaining: Option<u64>,
    pub(super) rng: Option<SmallRng>,
}

/// The verdict of the fault set on one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Verdict {
    Pass,
    Drop,
    Delay(Duration),
    Corrupt,
    Duplicate,
}

impl ActiveFault {
    pub(super) fn new(fault: Fault, since: Duration) -> Self {
        let rng = match fault.kind {
            FaultKind::DropWithProbability { seed, .. } => Some(SmallRng::seed_from_u64(seed)),
            _ => None,
        };
        Self {
            remaining: fault.max_frames,
            fault,
            since,
            rng,
        }
    }

    /// Whether the fault is in force at bus time `at`.
    pub(super) fn active_at(&self, at: Duration) -> bool {
        let started = at >= self.since;
        let not_ended = self
            .fault
            .duration
            .is_none_or(|duration| at < self.since + duration);
        started && not_ended && self.remaining != Some(0)
    }

    /// The fault's verdict on a matching frame; consumes one of its uses when it acts.
    /// `already_delayed` stops a delay fault from holding the same frame twice.
    pub(super) fn judge(&mut self, already_delayed: bool) -> Verdict {
        let verdict = match &self.fault.kind {
            FaultKind::Drop => Verdict::Drop,
            FaultKind::DropWithProbability { probability, .. } => {
                let probability = probability.clamp(0.0, 1.0);
                let dropped = self
                    .rng
                    .as_mut()
                    .is_some_and(|rng| rng.random_bool(probability));
                if dropped {
                    Verdict::Drop
                } else {
                    Verdict::Pass
                }
            }
            FaultKind::Delay(delay) if !already_delayed => Verdict::Delay(*delay),
            FaultKind::Delay(_) => Verdict::Pass,
            FaultKind::Corrupt => Verdict::Corrupt,
            FaultKind::Duplicate => Verdict::Duplicate,
        };
        if verdict != Verdict::Pass {
            if let Some(remaining) = self.remaining.as_mut() {
                *remaining = remaining.saturating_sub(1);
            }
        }
        verdict
    }
}

/// Run-time fault hooks of one virtual bus; cheap to clone, usable from any task.
///
/// Holding a `FaultHandle` does not keep the bus's wire task alive.
#[derive(Clone)]
pub struct FaultHandle {
    pub(super) shared: Arc<Shared>,
}

impl std::fmt::Debug for FaultHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaultHandle").finish_non_exhaustive()
    }
}

impl FaultHandle {
    /// Inject a fault; it applies to frames that start on the wire from now on.
    pub fn inject(&self, fault: Fault) -> FaultId {
        self.shared
            .with_state(|state, now| state.inject_fault(fault, now))
    }

    /// Remove an injected fault; false if it was not (or no longer) present.
    pub fn remove(&self, id: FaultId) -> bool {
        self.shared
            .with_state(|state, _| state.faults.remove(&id.0).is_some())
    }

    /// Remove every injected fault (bus-off periods already started keep running).
    pub fn clear(&self) {
        self.shared.with_state(|state, _| state.faults.clear());
    }

    /// Silence every node attached as `node`: its frames vanish before reaching the wire (its
    /// sends still succeed) until the returned fault is removed. It still receives.
    pub fn silence_node(&self, node: &str) -> FaultId {
        self.inject(Fault::drop(FrameFilter::Node(node.to_owned())))
    }

    /// Put every node attached as `node` into bus-off for `duration`: its queued frames are
    /// discarded, its sends fail with [`BusError::BusOff`](crate::BusError::BusOff) and it
    /// receives nothing until the period ends, after which it recovers by itself.
    /// Returns how many nodes were affected.
    pub fn bus_off(&self, node: &str, duration: Duration) -> usize {
        self.shared
            .with_state(|state, now| state.bus_off(node, now + duration))
    }
}
