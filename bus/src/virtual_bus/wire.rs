//! The wire model: per-node transmit queues, arbitration, bit timing, faults and delivery.
//!
//! The state is a pure function of what was queued when, so it is advanced lazily: every
//! operation first calls [`WireState::advance`] with the current bus time, which completes
//! every frame whose last bit has left the wire by then and arbitrates the frames that followed.
//! The wire task only sleeps until the next frame completes. Tokio timers have millisecond
//! resolution, so frames are timestamped from the model (start + bit time), never from the
//! moment a timer fired: a 111 µs frame is stamped 111 µs after it started even if the task
//! woke up at the next millisecond.

use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tokio::sync::{broadcast, mpsc, Notify};
use tokio::time::Instant;

use super::faults::{ActiveFault, Fault, FaultId, Verdict};
use super::stats::StatsCounter;
use crate::fine_timer::Sleeper;
use crate::timing::{bits_duration, frame_bits, phase_bits, phases_duration, StuffingPolicy};
use crate::{BusError, CanFrame, CanId, ReceivedFrame};

/// State shared by the bus handle, the nodes, the fault handle and the wire task.
pub(crate) struct Shared {
    state: Mutex<WireState>,
    /// Wakes the wire task when its next deadline may have moved earlier.
    pub(super) wake: Notify,
    /// Tokio instant of bus time zero.
    pub(super) start: Instant,
    /// What a frame's timestamp adds to bus time (the configuration's epoch).
    pub(super) epoch: Duration,
}

impl Shared {
    pub(super) fn new(state: WireState) -> Self {
        Self {
            epoch: state.params.epoch,
            state: Mutex::new(state),
            wake: Notify::new(),
            start: Instant::now(),
        }
    }

    /// Bus time: time elapsed since the bus was created.
    pub(super) fn now(&self) -> Duration {
        Instant::now().saturating_duration_since(self.start)
    }

    pub(super) fn lock(&self) -> MutexGuard<'_, WireState> {
        // A panic while holding the lock cannot leave the queues half-updated in a way that
        // matters more than losing the bus, so keep going with the inner state.
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Bring the wire up to date (without deciding arbitrations at this very instant, since
    /// other tasks may still queue frames for it), run `f`, then wake the wire task.
    pub(super) fn with_state<R>(&self, f: impl FnOnce(&mut WireState, Duration) -> R) -> R {
        let now = self.now();
        let result = {
            let mut state = self.lock();
            state.advance(now, false);
            f(&mut state, now)
        };
        self.wake.notify_one();
        result
    }
}

/// A frame waiting in a node's transmit queue.
struct Queued {
    frame: CanFrame,
    /// Its length on this wire, worked out once when it is queued (an exact stuffing pass is
    /// a few percent of a busy emulator's profile; planning and sending both need it).
    length: WireLength,
    /// Bus time from which it may compete for the bus.
    ready_at: Duration,
    /// Set once a delay fault has held it, so one fault delays a frame only once.
    delayed: bool,
}

/// A frame's length on the wire: bits and the time they take.
#[derive(Debug, Clone, Copy)]
struct WireLength {
    bits: u32,
    duration: Duration,
}

/// One attached node.
pub(super) struct NodeSlot {
    pub(super) name: String,
    receive_own: bool,
    capacity: usize,
    queue: VecDeque<Queued>,
    /// `None` once the node is closed or dropped: it neither sends nor receives any more.
    rx: Option<mpsc::UnboundedSender<ReceivedFrame>>,
    /// Bus time at which a bus-off period ends.
    bus_off_until: Option<Duration>,
}

impl NodeSlot {
    fn is_bus_off(&self, at: Duration) -> bool {
        self.bus_off_until.is_some_and(|until| at < until)
    }
}

/// What happens to the frame on the wire when it completes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fate {
    Deliver,
    Corrupt,
    Duplicate,
}

/// The frame currently on the wire.
struct InFlight {
    frame: CanFrame,
    node: usize,
    bits: u32,
    start: Duration,
    end: Duration,
    fate: Fate,
}

/// Wire parameters fixed at creation.
pub(super) struct WireParams {
    pub(super) bitrate_bps: u32,
    /// CAN FD data bit rate; `None` on a classic bus, which refuses CAN FD frames.
    pub(super) data_bitrate_bps: Option<u32>,
    pub(super) stuffing: StuffingPolicy,
    pub(super) epoch: Duration,
}

/// Everything the wire task owns, behind one lock.
pub(crate) struct WireState {
    params: WireParams,
    pub(super) nodes: Vec<NodeSlot>,
    in_flight: Option<InFlight>,
    /// Bus time at which the last frame (with its intermission) ended.
    free_at: Duration,
    pub(super) faults: BTreeMap<u64, ActiveFault>,
    next_fault_id: u64,
    pub(super) stats: StatsCounter,
    /// Taken when the wire task stops, which ends every tap.
    pub(super) tap: Option<broadcast::Sender<ReceivedFrame>>,
    /// Set when the bus handle and every node are gone.
    pub(super) shutdown: bool,
}

impl WireState {
    pub(super) fn new(params: WireParams, tap: broadcast::Sender<ReceivedFrame>) -> Self {
        Self {
            params,
            nodes: Vec::new(),
            in_flight: None,
            free_at: Duration::ZERO,
            faults: BTreeMap::new(),
            next_fault_id: 0,
            stats: StatsCounter::default(),
            tap: Some(tap),
            shutdown: false,
        }
    }

    pub(super) fn attach(
        &mut self,
        name: &str,
        receive_own: bool,
        capacity: usize,
    ) -> (usize, mpsc::UnboundedReceiver<ReceivedFrame>) {
        let (tx, rx) = mpsc::unbounded_channel();
        self.nodes.push(NodeSlot {
            name: name.to_owned(),
            receive_own,
            capacity,
            queue: VecDeque::new(),
            rx: Some(tx),
            bus_off_until: None,
        });
        (self.nodes.len() - 1, rx)
    }

    /// Queue a frame from `node` at bus time `now`, to compete for the wire from `ready_at`
    /// on (a firmware's turnaround later than `now`).
    pub(super) fn enqueue(
        &mut self,
        node: usize,
        frame: CanFrame,
        now: Duration,
        ready_at: Duration,
    ) -> Result<(), BusError> {
        let length = self.wire_time(&frame);
        let Some(slot) = self.nodes.get_mut(node) else {
            return Err(BusError::Closed);
        };
        if slot.rx.is_none() {
            return Err(BusError::Closed);
        }
        if frame.is_fd() && self.params.data_bitrate_bps.is_none() {
            return Err(fd_on_classic_bus(&slot.name, &frame));
        }
        if slot.is_bus_off(now) {
            return Err(BusError::BusOff);
        }
        if slot.queue.len() >= slot.capacity {
            self.stats.tx_queue_full += 1;
            return Err(BusError::TxQueueFull {
                capacity: slot.capacity,
            });
        }
        slot.queue.push_back(Queued {
            frame,
            length,
            ready_at: ready_at.max(now),
            delayed: false,
        });
        Ok(())
    }

    /// Whether a frame is on the wire right now (the wire task then sleeps until it ends).
    pub(super) fn has_frame_on_wire(&self) -> bool {
        self.in_flight.is_some()
    }

    /// Frames waiting in `node`'s transmit queue (the frame on the wire not included).
    pub(super) fn pending(&self, node: usize) -> usize {
        self.nodes.get(node).map_or(0, |slot| slot.queue.len())
    }

    /// Detach a node: it stops sending and receiving; its queued frames are discarded.
    pub(super) fn detach(&mut self, node: usize) {
        if let Some(slot) = self.nodes.get_mut(node) {
            slot.rx = None;
            slot.queue.clear();
        }
    }

    pub(super) fn inject_fault(&mut self, fault: Fault, now: Duration) -> FaultId {
        let id = self.next_fault_id;
        self.next_fault_id += 1;
        self.faults.insert(id, ActiveFault::new(fault, now));
        FaultId(id)
    }

    pub(super) fn bus_off(&mut self, name: &str, until: Duration) -> usize {
        let mut affected = 0;
        for slot in self.nodes.iter_mut().filter(|slot| slot.name == name) {
            self.stats.dropped += slot.queue.len() as u64;
            slot.queue.clear();
            slot.bus_off_until = Some(until);
            affected += 1;
        }
        affected
    }

    /// Run the wire up to bus time `now`: complete every frame that ended by then and start
    /// the ones that followed. Arbitrations at exactly `now` are decided only when `inclusive`
    /// (by the wire task, after letting other tasks queue their frames for this instant).
    /// Returns the bus time of the next event, or `None` when the wire is idle with nothing
    /// queued.
    pub(super) fn advance(&mut self, now: Duration, inclusive: bool) -> Option<Duration> {
        loop {
            if let Some(flight) = &self.in_flight {
                if flight.end > now {
                    return Some(flight.end);
                }
                if let Some(flight) = self.in_flight.take() {
                    self.complete(flight);
                }
                continue;
            }
            let earliest = self
                .nodes
                .iter()
                .filter_map(|slot| slot.queue.front().map(|queued| queued.ready_at))
                .min()?;
            let start = earliest.max(self.free_at);
            if start > now || (start == now && !inclusive) {
                return Some(start);
            }
            self.start_next(start);
        }
    }

    /// When the wire task must next look at the wire, given the next event [`Self::advance`]
    /// returned. A frame that will start later (a firmware's turnaround, an intermission) needs
    /// no wake-up at its start: the model is lazy, and whoever queues a frame before then
    /// brings the wire up to date and wakes the task to plan again. So with the wire idle and
    /// no fault that could drop, delay or repeat it, the task sleeps until the end of the frame
    /// that would win at `next` — one timer wake-up a frame instead of two (measured by
    /// `cargo bench --bench wire_latency`). Delivery instants and timestamps are the model's
    /// either way.
    pub(super) fn wake_at(&self, next: Duration) -> Duration {
        if self.in_flight.is_some() || !self.faults.is_empty() {
            return next;
        }
        let Some(node) = self.winner_at(next) else {
            return next;
        };
        self.nodes[node]
            .queue
            .front()
            .map_or(next, |queued| next + queued.length.duration)
    }

    /// The node whose queue head wins arbitration at `start`: the lowest arbitration key
    /// among the heads ready by then.
    fn winner_at(&self, start: Duration) -> Option<usize> {
        self.nodes
            .iter()
            .enumerate()
            .filter_map(|(index, slot)| {
                let head = slot.queue.front()?;
                (head.ready_at <= start).then_some((head.frame.id().arbitration_key(), index))
            })
            .min()
            .map(|(_, node)| node)
    }

    /// Arbitrate among the queue heads ready at `start` and put the winner on the wire (or
    /// let the fault set remove or hold it back).
    fn start_next(&mut self, start: Duration) {
        let Some(node) = self.winner_at(start) else {
            return;
        };
        let Some(queued) = self.nodes[node].queue.pop_front() else {
            return;
        };
        let verdict = self.judge(&queued, node, start);
        let fate = match verdict {
            Verdict::Drop => {
                self.stats.dropped += 1;
                return;
            }
            Verdict::Delay(delay) => {
                self.nodes[node].queue.push_front(Queued {
                    ready_at: start + delay,
                    delayed: true,
                    ..queued
                });
                return;
            }
            Verdict::Pass => Fate::Deliver,
            Verdict::Corrupt => Fate::Corrupt,
            Verdict::Duplicate => Fate::Duplicate,
        };
        self.put_on_wire(queued.frame, queued.length, node, start, fate);
    }

    /// The frame's length in bits and how long it occupies this wire.
    fn wire_time(&self, frame: &CanFrame) -> WireLength {
        let (bits, duration) = if frame.is_fd() {
            let phases = phase_bits(frame, self.params.stuffing);
            // Only queued on a bus with a data bit rate (see `enqueue`).
            let data_bps = self
                .params
                .data_bitrate_bps
                .unwrap_or(self.params.bitrate_bps);
            let duration = phases_duration(phases, self.params.bitrate_bps, data_bps);
            (phases.total(), duration)
        } else {
            let bits = frame_bits(frame, self.params.stuffing);
            (bits, bits_duration(bits, self.params.bitrate_bps))
        };
        WireLength { bits, duration }
    }

    fn put_on_wire(
        &mut self,
        frame: CanFrame,
        length: WireLength,
        node: usize,
        start: Duration,
        fate: Fate,
    ) {
        let end = start + length.duration;
        self.in_flight = Some(InFlight {
            frame,
            node,
            bits: length.bits,
            start,
            end,
            fate,
        });
    }

    /// The verdict of the active faults on a frame starting at `at`: the first fault (in
    /// injection order) that acts decides.
    fn judge(&mut self, queued: &Queued, node: usize, at: Duration) -> Verdict {
        let id: CanId = queued.frame.id();
        let name = &self.nodes[node].name;
        for fault in self.faults.values_mut() {
            if !fault.active_at(at) || !fault.fault.filter.matches(id, name) {
                continue;
            }
            let verdict = fault.judge(queued.delayed);
            if verdict != Verdict::Pass {
                return verdict;
            }
        }
        Verdict::Pass
    }

    fn complete(&mut self, flight: InFlight) {
        self.free_at = flight.end;
        self.stats.bits += u64::from(flight.bits);
        self.stats.busy += flight.end - flight.start;
        match flight.fate {
            Fate::Corrupt => self.stats.errors += 1,
            Fate::Deliver => self.deliver(&flight),
            Fate::Duplicate => {
                self.deliver(&flight);
                let length = WireLength {
                    bits: flight.bits,
                    duration: flight.end - flight.start,
                };
                self.put_on_wire(flight.frame, length, flight.node, flight.end, Fate::Deliver);
            }
        }
    }

    fn deliver(&mut self, flight: &InFlight) {
        let received = ReceivedFrame {
            frame: flight.frame,
            timestamp: self.params.epoch + flight.end,
        };
        self.stats.frames += 1;
        *self
            .stats
            .frames_by_id
            .entry(flight.frame.id())
            .or_insert(0) += 1;
        for (index, slot) in self.nodes.iter_mut().enumerate() {
            if index == flight.node && !slot.receive_own {
                continue;
            }
            if slot.is_bus_off(flight.end) {
                continue;
            }
            if let Some(rx) = &slot.rx {
                if rx.send(received).is_err() {
                    // The receiving half is gone with its node: stop delivering to it.
                    slot.rx = None;
                    slot.queue.clear();
                }
            }
        }
        if let Some(tap) = &self.tap {
            // No subscribers is fine: the tap is optional.
            let _ = tap.send(received);
        }
    }
}

/// The refusal of a CAN FD frame by a classic bus, naming the node that sent it.
fn fd_on_classic_bus(node: &str, frame: &CanFrame) -> BusError {
    BusError::Io {
        iface: node.to_owned(),
        source: std::io::Error::new(
            std::io::ErrorKind::Unsupported,
            format!(
                "CAN FD frame {} ({} bytes) refused: this virtual bus is classic CAN (a classic \
                 controller answers a CAN FD frame with an error frame); give the bus a data \
                 bit rate (VirtualBusConfig::data_bitrate_bps) to carry CAN FD",
                frame.id(),
                frame.len()
            ),
        ),
    }
}

/// The wire task: sleep until the next frame completes (or until woken), advance, repeat.
/// Exits when the bus and all its nodes are gone; an idle bus waits without spinning.
pub(super) async fn run_wire(shared: Arc<Shared>, mut sleeper: Sleeper) {
    loop {
        let next = {
            let mut state = shared.lock();
            if state.shutdown {
                state.tap = None;
                return;
            }
            state
                .advance(shared.now(), true)
                .map(|next| state.wake_at(next))
        };
        match next {
            Some(at) => {
                tokio::select! {
                    () = sleeper.sleep_until(shared.start + at) => {}
                    () = shared.wake.notified() => {}
                }
            }
            None => shared.wake.notified().await,
        }
        // Let every task that runs at this instant queue its frame before arbitrating, so
        // simultaneous senders compete as they do on a real bus.
        tokio::task::yield_now().await;
    }
}
