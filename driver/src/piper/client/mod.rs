//! The connection: one owner per bus, a receive task that decodes into state snapshots, a
//! link monitor, and the command / query API (in `commands` and `queries`).

mod builder;
mod commands;
mod link;
mod queries;
mod settings;

use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, RwLock};
use std::time::Duration;

use bus::{BusError, CanBus, CanFrame};
use tokio::sync::{broadcast, watch};
use tokio::task::JoinHandle;
use tokio::time::{sleep, Instant};

pub use builder::{BusOpener, DhSelection, FirmwareSelection, PiperBuilder, PiperConfig, Timeouts};

use super::codec::{FirmwareAssembler, FirmwareInfo, FirmwareVersion, Message, MitPacking};
use super::error::PiperError;
use super::kinematics::{forward_kinematics, DhVariant, LinkPose};
use super::state::{BusFault, PiperState, Stamped};
use builder::BusSource;
use link::Counters;

/// A reply to a query, as the receive task hands it to waiting callers.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Reply {
    /// A decoded reply frame (0x473, 0x476, 0x478, 0x47B, 0x47C, 0x47E, 0x488, CPV).
    Frame(Message),
    /// A complete 11-frame firmware reply.
    Firmware(FirmwareInfo),
}

/// Bus owners of this process: a driver claims its bus for its lifetime.
static OWNERS: Mutex<BTreeSet<String>> = Mutex::new(BTreeSet::new());

fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    // A poisoned lock only means another task panicked mid-update; the data is still usable.
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

pub(crate) struct Inner {
    bus: RwLock<Arc<dyn CanBus>>,
    opener: Option<BusOpener>,
    owner_key: String,
    pub(crate) config: PiperConfig,
    state: watch::Sender<PiperState>,
    messages: broadcast::Sender<Stamped<Message>>,
    replies: broadcast::Sender<Reply>,
    firmware: Mutex<FirmwareAssembler>,
    firmware_version: Mutex<Option<FirmwareVersion>>,
    last_joint_target_rad: Mutex<Option<[f64; 6]>>,
    led_counter: AtomicU8,
    counters: Mutex<Counters>,
    query_lock: tokio::sync::Mutex<()>,
    tasks: Mutex<Vec<JoinHandle<()>>>,
    connected: AtomicBool,
}

impl Drop for Inner {
    fn drop(&mut self) {
        for task in lock(&self.tasks).drain(..) {
            task.abort();
        }
        lock(&OWNERS).remove(&self.owner_key);
    }
}

/// A connected Piper arm. Cheap to clone: clones share one connection.
///
/// ```no_run
/// # async fn demo(node: std::sync::Arc<dyn bus::CanBus>) -> Result<(), driver::piper::PiperError> {
/// use driver::piper::{MotorSelect, MoveKind, PiperBuilder};
/// let piper = PiperBuilder::new(node).connect().await?;
/// piper.enable(MotorSelect::All).await?;
/// piper.move_joints_rad([0.2, 0.5, -0.5, 0.0, 0.3, 0.0], 50).await?;
/// piper.wait_for_arrival(0.01, std::time::Duration::from_secs(10)).await?;
/// println!("{:?}", piper.state().joints_rad());
/// piper.disconnect().await;
/// # Ok(()) }
/// ```
#[derive(Clone)]
pub struct Piper {
    pub(crate) inner: Arc<Inner>,
}

impl std::fmt::Debug for Piper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Piper")
            .field("bus", &self.inner.owner_key)
            .finish_non_exhaustive()
    }
}

impl Piper {
    async fn connect(builder: PiperBuilder) -> Result<Self, PiperError> {
        let (bus, opener, owner_key) = match builder.source {
            BusSource::Shared(bus) => {
                let key = format!("{}@{:p}", bus.name(), Arc::as_ptr(&bus) as *const ());
                (bus, None, key)
            }
            BusSource::Opener { name, open } => {
                let key = format!("iface:{name}");
                if lock(&OWNERS).contains(&key) {
                    return Err(PiperError::AlreadyOwned { bus: name });
                }
                (open()?, Some(open), key)
            }
        };
        if !lock(&OWNERS).insert(owner_key.clone()) {
            return Err(PiperError::AlreadyOwned {
                bus: bus.name().to_owned(),
            });
        }
        let forced = match builder.config.firmware {
            FirmwareSelection::Forced(version) => Some(version),
            FirmwareSelection::Auto => None,
        };
        let inner = Arc::new(Inner {
            bus: RwLock::new(bus),
            opener,
            owner_key,
            config: builder.config,
            state: watch::channel(PiperState::default()).0,
            messages: broadcast::channel(1024).0,
            replies: broadcast::channel(256).0,
            firmware: Mutex::new(FirmwareAssembler::new()),
            firmware_version: Mutex::new(forced),
            last_joint_target_rad: Mutex::new(None),
            led_counter: AtomicU8::new(0),
            counters: Mutex::new(Counters::default()),
            query_lock: tokio::sync::Mutex::new(()),
            tasks: Mutex::new(Vec::new()),
            connected: AtomicBool::new(true),
        });
        let piper = Self { inner };
        piper.start_tasks();
        tracing::info!(bus = %piper.inner.owner_key, "piper driver connected");
        if let Some(wait) = piper.inner.config.timeouts.first_feedback {
            let result = piper
                .wait_for(|s| s.link.last_feedback.is_some(), wait, "first feedback")
                .await;
            if let Err(error) = result {
                piper.disconnect().await;
                return Err(error);
            }
        }
        if forced.is_none() {
            if let Err(error) = piper.query_firmware().await {
                tracing::warn!(%error, "firmware version unknown; assuming pre-S-V1.8-8 MIT packing");
            }
        }
        Ok(piper)
    }

    fn start_tasks(&self) {
        let rx = tokio::spawn(receive_task(Arc::downgrade(&self.inner)));
        let monitor = tokio::spawn(link::monitor_task(Arc::downgrade(&self.inner)));
        lock(&self.inner.tasks).extend([rx, monitor]);
    }

    /// Stop the background tasks and release the bus (closing it if the driver opened it
    /// through an opener). Later calls fail with [`PiperError::Disconnected`].
    pub async fn disconnect(&self) {
        if !self.inner.connected.swap(false, Ordering::AcqRel) {
            return;
        }
        let tasks: Vec<_> = lock(&self.inner.tasks).drain(..).collect();
        for task in tasks {
            task.abort();
            // Awaiting makes sure the task no longer runs when we return.
            let _ = task.await;
        }
        // Close only what the driver opened itself; a shared endpoint belongs to the caller.
        if self.inner.opener.is_some() {
            self.bus().close().await;
        }
        lock(&OWNERS).remove(&self.inner.owner_key);
        tracing::info!(bus = %self.inner.owner_key, "piper driver disconnected");
    }

    /// True until [`Piper::disconnect`].
    pub fn is_connected(&self) -> bool {
        self.inner.connected.load(Ordering::Acquire)
    }

    /// Re-open the bus (through the builder's opener, if any) and restart the background
    /// tasks. With a shared bus endpoint only the tasks restart.
    pub async fn reconnect(&self) -> Result<(), PiperError> {
        let tasks: Vec<_> = lock(&self.inner.tasks).drain(..).collect();
        for task in tasks {
            task.abort();
            let _ = task.await;
        }
        if let Some(open) = &self.inner.opener {
            let bus = open()?;
            *self.inner.bus.write().unwrap_or_else(|p| p.into_inner()) = bus;
        }
        self.inner.connected.store(true, Ordering::Release);
        self.inner.state.send_modify(|s| {
            s.link.reconnects += 1;
            s.link.bus_fault = None;
        });
        self.start_tasks();
        Ok(())
    }

    fn bus(&self) -> Arc<dyn CanBus> {
        self.inner
            .bus
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    fn ensure_connected(&self) -> Result<(), PiperError> {
        if self.is_connected() {
            Ok(())
        } else {
            Err(PiperError::Disconnected)
        }
    }

    /// Send one raw frame, retrying while the transmit queue is full (up to the send
    /// timeout). The escape hatch for frames the typed API does not cover; build them with
    /// [`super::codec`].
    pub async fn send_frame(&self, frame: CanFrame) -> Result<(), PiperError> {
        self.ensure_connected()?;
        let deadline = Instant::now() + self.inner.config.timeouts.send;
        loop {
            match self.bus().send(frame).await {
                Ok(()) => return Ok(()),
                Err(BusError::TxQueueFull { .. }) if Instant::now() < deadline => {
                    // One frame takes ~0.13 ms at 1 Mbit/s: a millisecond frees several slots.
                    sleep(Duration::from_millis(1)).await;
                }
                Err(error) => {
                    record_fault(&self.inner, &error);
                    return Err(error.into());
                }
            }
        }
    }

    /// Send several frames in order.
    pub async fn send_frames(&self, frames: &[CanFrame]) -> Result<(), PiperError> {
        for frame in frames {
            self.send_frame(*frame).await?;
        }
        Ok(())
    }

    /// A copy of the current state.
    pub fn state(&self) -> PiperState {
        self.inner.state.borrow().clone()
    }

    /// A watch receiver that sees every state update (`changed().await`, then `borrow()`).
    pub fn subscribe_state(&self) -> watch::Receiver<PiperState> {
        self.inner.state.subscribe()
    }

    /// Every decoded codec message as it arrives, stamped with the frame count since connect
    /// as `seq` (a lagging receiver loses the oldest). A wire-level tap for tools and
    /// recorders; [`Piper::state`] carries the same information in SI units.
    pub fn subscribe_messages(&self) -> broadcast::Receiver<Stamped<Message>> {
        self.inner.messages.subscribe()
    }

    /// Link health: feedback seen within the link timeout and no bus fault.
    pub fn is_ok(&self) -> bool {
        let state = self.inner.state.borrow();
        link::is_fresh(&state.link, self.inner.config.timeouts.link)
    }

    /// The firmware version in use (forced, or detected from 0x4AF).
    pub fn firmware_version(&self) -> Option<FirmwareVersion> {
        *lock(&self.inner.firmware_version)
    }

    /// The MIT packing in use: from the firmware, 8-bit + check nibble while unknown.
    pub(crate) fn mit_packing(&self) -> MitPacking {
        self.firmware_version()
            .map_or(MitPacking::Torque8Crc, FirmwareVersion::mit_packing)
    }

    /// The DH table in use.
    pub fn dh_variant(&self) -> DhVariant {
        match self.inner.config.dh {
            DhSelection::Fixed(variant) => variant,
            DhSelection::Auto => match self.firmware_version() {
                Some(version) if !version.uses_dh_offset() => DhVariant::Legacy,
                _ => DhVariant::Offset,
            },
        }
    }

    /// Forward kinematics of the current joint feedback (each link frame), like the SDK's
    /// `GetFK`; `None` before the first joint feedback.
    pub fn forward_kinematics(&self) -> Option<[LinkPose; 6]> {
        let q = self.state().joints_rad()?;
        Some(forward_kinematics(q, self.dh_variant()))
    }

    /// Wait until `predicate` holds for a state snapshot; returns that snapshot.
    pub async fn wait_for(
        &self,
        predicate: impl Fn(&PiperState) -> bool,
        timeout: Duration,
        what: &'static str,
    ) -> Result<PiperState, PiperError> {
        let mut rx = self.inner.state.subscribe();
        let deadline = Instant::now() + timeout;
        loop {
            {
                let state = rx.borrow_and_update();
                if predicate(&state) {
                    return Ok(state.clone());
                }
            }
            match tokio::time::timeout_at(deadline, rx.changed()).await {
                Ok(Ok(())) => {}
                Ok(Err(_)) => return Err(PiperError::Disconnected),
                Err(_) => {
                    return Err(PiperError::Timeout {
                        what,
                        waited: timeout,
                    })
                }
            }
        }
    }
}

fn record_fault(inner: &Inner, error: &BusError) {
    let fault = match error {
        BusError::BusOff => BusFault::BusOff,
        BusError::InterfaceDown { .. } | BusError::NoSuchInterface { .. } => {
            BusFault::InterfaceDown
        }
        BusError::Closed => BusFault::Closed,
        BusError::TxQueueFull { .. } => BusFault::TxQueueFull,
        BusError::Io { source, .. } => BusFault::Io(source.to_string()),
        BusError::Unsupported => BusFault::Io(error.to_string()),
    };
    tracing::warn!(?fault, "piper bus fault");
    inner.state.send_modify(|s| s.link.bus_fault = Some(fault));
}

/// Decode every received frame into the state until the driver goes away.
async fn receive_task(weak: std::sync::Weak<Inner>) {
    let mut backoff = Duration::from_millis(10);
    loop {
        let Some(inner) = weak.upgrade() else { return };
        let bus = inner.bus.read().unwrap_or_else(|p| p.into_inner()).clone();
        // Do not hold the driver alive while waiting for a frame.
        drop(inner);
        let result = bus.recv().await;
        let Some(inner) = weak.upgrade() else { return };
        match result {
            Ok(received) => {
                backoff = Duration::from_millis(10);
                handle_frame(&inner, received.frame, received.timestamp);
            }
            Err(error) => {
                if !inner.connected.load(Ordering::Acquire) {
                    return;
                }
                record_fault(&inner, &error);
                let reopen = matches!(
                    error,
                    BusError::InterfaceDown { .. }
                        | BusError::NoSuchInterface { .. }
                        | BusError::Io { .. }
                        | BusError::Closed
                );
                if matches!(error, BusError::Closed) && inner.opener.is_none() {
                    // A shared endpoint that was closed will not come back.
                    return;
                }
                drop(inner);
                sleep(backoff).await;
                backoff = (backoff * 2).min(Duration::from_secs(1));
                if reopen {
                    let Some(inner) = weak.upgrade() else { return };
                    if let Some(open) = &inner.opener {
                        match open() {
                            Ok(bus) => {
                                *inner.bus.write().unwrap_or_else(|p| p.into_inner()) = bus;
                                inner.state.send_modify(|s| {
                                    s.link.reconnects += 1;
                                    s.link.bus_fault = None;
                                });
                                tracing::info!("piper bus re-opened");
                            }
                            Err(error) => tracing::warn!(%error, "re-opening the bus failed"),
                        }
                    }
                }
            }
        }
    }
}

fn handle_frame(inner: &Inner, frame: CanFrame, bus_time: Duration) {
    let now = Instant::now();
    let decoded = super::codec::decode(&frame);
    let seq = lock(&inner.counters).count(frame.raw_id());
    let message = match decoded {
        Ok(Some(message)) => message,
        Ok(None) => return,
        Err(error) => {
            tracing::debug!(%error, "malformed piper frame");
            inner.state.send_modify(|s| s.link.malformed += 1);
            return;
        }
    };
    if inner.config.abnormal_filter && super::state::is_abnormal(&message) {
        inner.state.send_modify(|s| s.link.filtered += 1);
        return;
    }
    let mut reply = None;
    match &message {
        Message::FirmwarePart(part) => {
            if let Some(info) = lock(&inner.firmware).push(part) {
                inner.state.send_modify(|s| {
                    s.firmware = Some(info.clone());
                    s.link.last_feedback = Some(now);
                    s.link.bus_fault = None;
                });
                reply = Some(Reply::Firmware(info));
            }
        }
        Message::JointLimits(_)
        | Message::JointMaxAcc(_)
        | Message::Ack(_)
        | Message::EndParams(_)
        | Message::Collision(_)
        | Message::GripperTeach(_)
        | Message::Assist(_)
        | Message::Cpv(_) => reply = Some(Reply::Frame(message.clone())),
        _ => {}
    }
    inner.state.send_modify(|s| {
        s.apply(&message, bus_time, now);
        s.link.last_feedback = Some(now);
        s.link.bus_fault = None;
    });
    if inner.messages.receiver_count() > 0 {
        let _ = inner.messages.send(Stamped {
            value: message,
            bus_time,
            received_at: now,
            seq,
        });
    }
    if let Some(reply) = reply {
        // No receiver simply means nobody is waiting for this reply.
        let _ = inner.replies.send(reply);
    }
}
