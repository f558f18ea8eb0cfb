//! An in-process CAN bus that models the wire.
//!
//! Every attached [`VirtualNode`] receives every frame but its own (unless created with
//! [`NodeOptions::receive_own`]). One wire task owns the model:
//!
//! - **Timing**: a frame occupies `bits / bitrate` of bus time, its length counted by
//!   [`frame_bits`](crate::timing::frame_bits) under the configured
//!   [`StuffingPolicy`] (default: exact stuff bits). Frames follow each other back to back.
//! - **CAN FD**: a bus given a data bit rate ([`VirtualBusConfig::data_bitrate_bps`]) carries
//!   CAN FD frames next to classic ones: an FD frame's arbitration phase takes the nominal bit
//!   rate, its data phase (with BRS) the data bit rate, as
//!   [`phase_bits`](crate::timing::phase_bits) splits it. A bus without a data bit rate is a
//!   classic bus: sending a CAN FD frame on it fails at once with [`BusError::Io`] naming the
//!   node (where a classic controller on a real bus would answer the frame with an error
//!   frame), and nothing reaches the wire.
//! - **Arbitration**: whenever the wire becomes free, the head frames of all node queues that
//!   were ready by then compete and the lowest [`CanId::arbitration_key`](crate::CanId) wins;
//!   ties between nodes go to the node attached first. Each node sends its own frames in FIFO
//!   order, like a controller with one transmit mailbox fed by a queue.
//! - **Queues**: each node has a bounded transmit queue (default 10 frames, the frame on the
//!   wire not counted); sending into a full queue is [`BusError::TxQueueFull`]. Receive queues
//!   are unbounded and never hold up the wire.
//! - **Timestamps**: `config.epoch` + bus time at which the frame's last bit (including the
//!   intermission) left the wire. Bus time is tokio time since the bus was created, so under a
//!   paused clock runs are deterministic: the same run gives identical timestamps and order.
//! - **Faults**: see [`FaultHandle`].
//!
//! The wire task ends when the [`VirtualBus`] and all its nodes have been dropped.

mod faults;
mod stats;
mod wire;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use async_trait::async_trait;
use tokio::sync::{broadcast, mpsc, Mutex as AsyncMutex};

pub use crate::timing::StuffingPolicy;
pub use faults::{Fault, FaultHandle, FaultId, FaultKind, FrameFilter};
pub use stats::BusStats;
use wire::{Shared, WireParams, WireState};

use crate::fine_timer::FineTimer;
use crate::{BusError, CanBus, CanFrame, ReceivedFrame};

/// How a virtual bus behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualBusConfig {
    /// Bit rate of the modelled wire (default 1 Mbit/s), the nominal (arbitration) bit rate
    /// of CAN FD. Zero is treated as 1 bit/s.
    pub bitrate_bps: u32,
    /// CAN FD data-phase bit rate, used by FD frames with BRS set (FD frames without BRS run
    /// at `bitrate_bps` throughout). `None` (the default) is a classic CAN bus, which refuses
    /// CAN FD frames. Zero is treated as 1 bit/s.
    pub data_bitrate_bps: Option<u32>,
    /// Default transmit queue length per node (default 10). Zero is treated as 1.
    pub tx_queue_len: usize,
    /// Added to bus time to form timestamps (default zero; use a Unix time to make candump
    /// logs look like real captures).
    pub epoch: Duration,
    /// Which stuff bits frame lengths include (default [`StuffingPolicy::Exact`]).
    pub stuffing: StuffingPolicy,
    /// Frames a tap may fall behind before it misses some (default 16384).
    pub tap_capacity: usize,
    /// What the wire sleeps on between frames (default [`FineTimer::Auto`]: a timerfd in real
    /// time on a multi-thread runtime; give the [`VirtualTimeline`](crate::fine_timer::VirtualTimeline)
    /// in virtual time so frames arrive at the microsecond, not on the next millisecond).
    pub timer: FineTimer,
}

impl Default for VirtualBusConfig {
    fn default() -> Self {
        Self {
            bitrate_bps: 1_000_000,
            data_bitrate_bps: None,
            tx_queue_len: 10,
            epoch: Duration::ZERO,
            stuffing: StuffingPolicy::Exact,
            tap_capacity: 16_384,
            timer: FineTimer::Auto,
        }
    }
}

/// Per-node options for [`VirtualBus::attach_with`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct NodeOptions {
    /// Also receive the node's own frames once they complete on the wire (SocketCAN's
    /// `recv_own_msgs`).
    pub receive_own: bool,
    /// This node's transmit queue length; `None` uses the bus default.
    pub tx_queue_len: Option<usize>,
}

/// Keeps the wire task running while any bus handle or node exists.
struct Owner {
    shared: Arc<Shared>,
}

impl Drop for Owner {
    /// Frames that finished on the wire by now are still delivered (and tapped); a frame
    /// still on the wire, or queued, is lost with the bus.
    fn drop(&mut self) {
        let now = self.shared.now();
        let mut state = self.shared.lock();
        state.advance(now, false);
        state.shutdown = true;
        drop(state);
        self.shared.wake.notify_one();
    }
}

/// A virtual CAN bus. Cloning gives another handle to the same bus.
#[derive(Clone)]
pub struct VirtualBus {
    owner: Arc<Owner>,
    config: Arc<VirtualBusConfig>,
}

impl std::fmt::Debug for VirtualBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualBus")
            .field("config", &self.config)
            .finish_non_exhaustive()
    }
}

impl VirtualBus {
    /// Create a bus and spawn its wire task on the current tokio runtime.
    ///
    /// # Panics
    /// When called outside a tokio runtime (like `tokio::spawn`).
    pub fn new(config: VirtualBusConfig) -> Self {
        let (tap, _) = broadcast::channel(config.tap_capacity.max(1));
        let params = WireParams {
            bitrate_bps: config.bitrate_bps.max(1),
            data_bitrate_bps: config.data_bitrate_bps.map(|bps| bps.max(1)),
            stuffing: config.stuffing,
            epoch: config.epoch,
        };
        let shared = Arc::new(Shared::new(WireState::new(params, tap)));
        tokio::spawn(wire::run_wire(Arc::clone(&shared), config.timer.sleeper()));
        Self {
            owner: Arc::new(Owner { shared }),
            config: Arc::new(config),
        }
    }

    /// The configuration the bus was created with.
    pub fn config(&self) -> &VirtualBusConfig {
        &self.config
    }

    /// Attach a node with default options.
    pub fn attach(&self, name: &str) -> VirtualNode {
        self.attach_with(name, NodeOptions::default())
    }

    /// Attach a node. It receives frames that complete on the wire from now on.
    pub fn attach_with(&self, name: &str, options: NodeOptions) -> VirtualNode {
        let capacity = options
            .tx_queue_len
            .unwrap_or(self.config.tx_queue_len)
            .max(1);
        let shared = &self.owner.shared;
        let (index, rx) =
            shared.with_state(|state, _| state.attach(name, options.receive_own, capacity));
        VirtualNode {
            inner: Arc::new(NodeInner {
                owner: Arc::clone(&self.owner),
                index,
                name: name.to_owned(),
                rx: AsyncMutex::new(rx),
                closed: AtomicBool::new(false),
            }),
        }
    }

    /// A receiver of every frame that completes on the wire, from now on.
    pub fn tap(&self) -> broadcast::Receiver<ReceivedFrame> {
        let state = self.owner.shared.lock();
        match &state.tap {
            Some(tap) => tap.subscribe(),
            // Unreachable while a bus handle exists; an already-closed receiver is the honest
            // answer anyway.
            None => broadcast::channel(1).1,
        }
    }

    /// Bus-load statistics so far.
    pub fn stats(&self) -> BusStats {
        self.owner
            .shared
            .with_state(|state, now| state.stats.snapshot(now))
    }

    /// Start a new statistics window now.
    pub fn reset_stats(&self) {
        self.owner.shared.with_state(|state, now| {
            state.stats = stats::StatsCounter {
                since: now,
                ..Default::default()
            };
        });
    }

    /// The run-time fault hooks of this bus.
    pub fn faults(&self) -> FaultHandle {
        FaultHandle {
            shared: Arc::clone(&self.owner.shared),
        }
    }

    /// The current bus timestamp: epoch + time since the bus was created.
    pub fn now(&self) -> Duration {
        self.config.epoch + self.owner.shared.now()
    }
}

struct NodeInner {
    owner: Arc<Owner>,
    index: usize,
    name: String,
    rx: AsyncMutex<mpsc::UnboundedReceiver<ReceivedFrame>>,
    closed: AtomicBool,
}

impl Drop for NodeInner {
    fn drop(&mut self) {
        self.owner
            .shared
            .with_state(|state, _| state.detach(self.index));
    }
}

/// A node attached to a [`VirtualBus`]. Clones are the same node (shared queues), so one clone
/// can receive while others send.
#[derive(Clone)]
pub struct VirtualNode {
    inner: Arc<NodeInner>,
}

impl std::fmt::Debug for VirtualNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualNode")
            .field("name", &self.inner.name)
            .field("index", &self.inner.index)
            .finish_non_exhaustive()
    }
}

impl VirtualNode {
    /// Frames waiting in this node's transmit queue (the one on the wire not counted).
    pub fn pending_tx(&self) -> usize {
        self.shared()
            .with_state(|state, _| state.pending(self.inner.index))
    }

    /// The next received frame if one is waiting, without waiting.
    pub fn try_recv(&self) -> Result<Option<ReceivedFrame>, BusError> {
        self.catch_up();
        let Ok(mut rx) = self.inner.rx.try_lock() else {
            // Another task is inside `recv`: nothing for us.
            return Ok(None);
        };
        match rx.try_recv() {
            Ok(_) if self.inner.closed.load(Ordering::Acquire) => Err(BusError::Closed),
            Ok(frame) => Ok(Some(frame)),
            Err(mpsc::error::TryRecvError::Empty) => Ok(None),
            Err(mpsc::error::TryRecvError::Disconnected) => Err(BusError::Closed),
        }
    }

    /// Deliver every frame that has finished on the wire by now. The wire task would do it
    /// too, but timers fire at millisecond resolution and possibly after this task runs.
    fn catch_up(&self) {
        let shared = self.shared();
        let now = shared.now();
        shared.lock().advance(now, false);
    }

    fn shared(&self) -> &Shared {
        &self.inner.owner.shared
    }
}

#[async_trait]
impl CanBus for VirtualNode {
    async fn send(&self, frame: CanFrame) -> Result<(), BusError> {
        self.send_after(frame, Duration::ZERO).await
    }

    async fn send_after(&self, frame: CanFrame, delay: Duration) -> Result<(), BusError> {
        let shared = self.shared();
        let now = shared.now();
        let wire_idle = {
            let mut state = shared.lock();
            state.advance(now, false);
            state.enqueue(self.inner.index, frame, now, now + delay)?;
            // With a frame on the wire the wire task already sleeps until it ends; otherwise
            // this frame may start now and the wire task must arbitrate.
            !state.has_frame_on_wire()
        };
        if wire_idle {
            shared.wake.notify_one();
        }
        Ok(())
    }

    fn since_received(&self, received: &ReceivedFrame) -> Duration {
        let shared = self.shared();
        (shared.epoch + shared.now()).saturating_sub(received.timestamp)
    }

    async fn recv(&self) -> Result<ReceivedFrame, BusError> {
        if self.inner.closed.load(Ordering::Acquire) {
            return Err(BusError::Closed);
        }
        self.catch_up();
        let mut rx = self.inner.rx.lock().await;
        match rx.recv().await {
            Some(frame) if !self.inner.closed.load(Ordering::Acquire) => Ok(frame),
            _ => Err(BusError::Closed),
        }
    }

    async fn close(&self) {
        self.inner.closed.store(true, Ordering::Release);
        // Dropping the node's sender wakes a pending `recv`.
        self.shared()
            .with_state(|state, _| state.detach(self.inner.index));
    }

    fn name(&self) -> &str {
        &self.inner.name
    }
}

#[cfg(test)]
mod tests;
