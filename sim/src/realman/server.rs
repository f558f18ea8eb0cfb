//! The emulator's transport: a TCP listener (real time) or in-memory duplex streams (virtual
//! time) feeding one [`Controller`], a 1 kHz core task, and the UDP realtime push.
//!
//! Every connection runs the same generic code over `AsyncRead + AsyncWrite`: a reader that
//! splits requests ([`Splitter`]), answers them under the controller lock and queues the reply,
//! and a writer that writes each queued message (reply or event) as its own write (compact JSON
//! and CRLF). Replies and events share the client's queue, so an acknowledgement always
//! precedes the arrival event of its move and the two never share a write.
//!
//! What a hostile or broken client cannot do:
//! - make a web page's request run: every byte read passes the shared
//!   [`bus::socketcand::http_guard::HttpGuard`] before the splitter sees it, so a
//!   connection that opens with an HTTP request line (a browser's `fetch` to this port) or
//!   carries `Host:`/`Origin:` lines is closed with nothing in it acted on;
//! - grow memory by not reading its replies: the queue holds at most [`CLIENT_QUEUE`]
//!   messages; while it is nearly full the reader stops reading that client (TCP then slows
//!   the client down), and a client whose queue has no room left for an event is dropped;
//! - hold a connection slot for ever: a connection on which no byte moved either way for
//!   [`EmulatorConfig::idle_timeout`] is closed, and when every slot is taken a newcomer
//!   takes the slot of the client idle longest, if that one has been idle for
//!   [`EVICT_IDLE_AFTER`].

use std::collections::BTreeMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, DuplexStream};
use tokio::net::{TcpListener, UdpSocket};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::{sleep, sleep_until, Instant};

use super::controller::{
    Answer, ArmSnapshot, ClientId, Controller, ControllerConfig, ControllerError,
};
use super::faults::{FaultError, RealmanFault, RealmanFaultKind};
use super::framing::{Splitter, Unit, MAX_REQUEST_BYTES};
use super::params::{PushConfig, StateFileError};
use super::push::{self, Datagram, PushFaults, PushSink, PushStats};
use crate::supervise::{DeathWatch, Supervisor};
use bus::socketcand::http_guard::HttpGuard;

/// Default most simultaneous connections.
pub const DEFAULT_MAX_CONNECTIONS: usize = 64;
/// Ticks run at most per wake-up when catching up after a stall (1 s of physics).
const MAX_CATCH_UP_TICKS: u64 = 1000;
/// Lateness that counts as an overrun, ms (one push period).
const OVERRUN_SLACK_MS: u64 = 5;
/// Read buffer per connection.
const READ_CHUNK: usize = 16 * 1024;
/// Capacity of an in-memory stream's pipe, bytes.
const DUPLEX_BYTES: usize = 256 * 1024;
/// Most messages (replies and events) queued for one client. Replies are at most a few KiB,
/// so a client that never reads costs at most about a MiB here (plus the kernel's buffers).
pub const CLIENT_QUEUE: usize = 256;
/// Slots of a client's queue kept for events: the reader takes a request only while more
/// than this many are free, so the events of the moves a client started still fit when it
/// is slow to read; a client whose queue has no room for an event is dropped.
const EVENT_HEADROOM: usize = 64;
/// Default of [`EmulatorConfig::idle_timeout`]: five minutes. The vendor SDK sends nothing
/// on its TCP connection while a program waits (for user input, or for the UDP push in its
/// callback mode), and the controller keeps such a connection, so the limit is long enough
/// for an interactive session to pause; it frees the slot of a client that vanished without
/// closing (a killed VM, a pulled cable) or leaked its socket. At the cap, a newcomer does not
/// wait that long (see [`EVICT_IDLE_AFTER`]).
pub const DEFAULT_IDLE_TIMEOUT: Duration = Duration::from_secs(300);
/// When every slot is taken, the client idle the longest gives its slot to a newcomer if it
/// has been idle at least this long (ten seconds: twenty times the SDK's reply timeout, so a
/// client in the middle of an exchange is never the one evicted).
pub const EVICT_IDLE_AFTER: Duration = Duration::from_secs(10);

/// Real TCP/UDP sockets or in-memory streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transport {
    /// Listen on this address (port 0 = any free port); push over UDP.
    Tcp(SocketAddr),
    /// Clients call [`RealmanHandle::connect`]; datagrams go to [`RealmanHandle::take_datagrams`].
    InMemory,
}

/// How to start an emulator.
#[derive(Debug, Clone)]
pub struct EmulatorConfig {
    /// The controller.
    pub controller: ControllerConfig,
    /// Most simultaneous connections; further ones are closed at once.
    pub max_connections: usize,
    /// Physics steps (1 ms) per wake-up of the core task (1–10).
    pub ticks_per_wake: u32,
    /// Seed of the random faults (UDP loss).
    pub seed: u64,
    /// A connection on which no byte moved either way for this long is closed (`None`:
    /// never). Default [`DEFAULT_IDLE_TIMEOUT`].
    pub idle_timeout: Option<Duration>,
}

impl EmulatorConfig {
    /// Defaults around a controller configuration.
    pub fn new(controller: ControllerConfig) -> Self {
        Self {
            controller,
            max_connections: DEFAULT_MAX_CONNECTIONS,
            ticks_per_wake: 1,
            seed: 0,
            idle_timeout: Some(DEFAULT_IDLE_TIMEOUT),
        }
    }
}

/// Why the emulator could not start or a client could not connect.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// The controller did not boot.
    #[error(transparent)]
    Controller(#[from] ControllerError),
    /// A socket could not be bound.
    #[error("cannot bind {addr}: {source}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// [`RealmanHandle::connect`] on an emulator that listens on TCP.
    #[error("this emulator listens on TCP; connect a socket to {addr}")]
    NotInMemory {
        /// Where it listens.
        addr: SocketAddr,
    },
    /// No tokio runtime is running.
    #[error("the Realman emulator needs a tokio runtime")]
    NoRuntime,
}

/// Transport counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ServerStats {
    /// Connections admitted.
    pub accepted: u64,
    /// Connections closed at once because the cap was reached.
    pub refused: u64,
    /// Connections closed for an over-long request.
    pub oversize: u64,
    /// Requests that were not valid JSON, and junk outside objects.
    pub malformed: u64,
    /// Requests with an unknown command.
    pub unknown: u64,
    /// Connections closed because they carried HTTP (a web page's request).
    pub http_refused: u64,
    /// Connections closed after [`EmulatorConfig::idle_timeout`] without traffic.
    pub idle_closed: u64,
    /// Connections that gave their slot to a newcomer at the cap (idle the longest).
    pub evicted: u64,
    /// Connections dropped because their queue had no room for an event (not reading).
    pub slow_dropped: u64,
    /// Wake-ups of the core task that came more than one push period (5 ms) late; the missed
    /// steps still ran, their push datagrams coalesced into one.
    pub overruns: u64,
    /// Push datagrams.
    pub push: PushStats,
}

/// One message for a client's writer.
#[derive(Debug)]
struct Outgoing {
    text: String,
}

struct Client {
    peer: SocketAddr,
    tx: mpsc::Sender<Outgoing>,
    /// Set to the reason when the connection must end now (a fault, eviction, not reading).
    kill: watch::Sender<Option<&'static str>>,
    /// Last time a byte moved either way, ms since [`Shared::epoch`].
    active_ms: Arc<AtomicU64>,
}

impl Client {
    fn end(&self, reason: &'static str) {
        self.kill.send_if_modified(|r| {
            let first = r.is_none();
            if first {
                *r = Some(reason);
            }
            first
        });
    }

    fn ending(&self) -> bool {
        self.kill.borrow().is_some()
    }
}

/// When a connection was last active, shared by its reader and writer.
#[derive(Clone)]
struct Activity {
    epoch: Instant,
    ms: Arc<AtomicU64>,
}

impl Activity {
    fn touch(&self) {
        let now = (Instant::now() - self.epoch).as_millis() as u64;
        self.ms.fetch_max(now, Ordering::Relaxed);
    }

    fn last(&self) -> Instant {
        self.epoch + Duration::from_millis(self.ms.load(Ordering::Relaxed))
    }
}

/// Faults applied by the transport.
#[derive(Debug, Default)]
struct WireFaults {
    reply_delay: Option<Duration>,
    truncate_next: u32,
}

struct Shared {
    core: Mutex<Controller>,
    clients: Mutex<BTreeMap<ClientId, Client>>,
    wire: Mutex<WireFaults>,
    push_faults: Mutex<PushFaults>,
    stats: Mutex<ServerStats>,
    next_client: AtomicU64,
    max_connections: usize,
    idle_timeout: Option<Duration>,
    /// Origin of the clients' activity times.
    epoch: Instant,
    stop: watch::Receiver<bool>,
    /// Listening on a non-loopback address: the push goes only to connected clients.
    public: bool,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while holding a lock must not take the whole emulator down with it.
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Apply `fault` to the transport or the controller.
fn inject_fault(shared: &Shared, fault: RealmanFault) -> Result<(), FaultError> {
    // The fault table's ranges, here too: every front end (scenarios, web view, Python, Rust
    // callers) reaches the emulator through this function.
    fault.check()?;
    tracing::info!(fault = fault.name(), "Realman fault injected");
    match fault {
        RealmanFault::ConnectionDrop { peer_ip } => {
            for client in lock(&shared.clients).values() {
                if peer_ip.is_none_or(|ip| ip == client.peer.ip()) {
                    client.end("dropped by fault");
                }
            }
        }
        RealmanFault::ReplyDelay { delay_ms } => {
            lock(&shared.wire).reply_delay = Some(Duration::from_millis(delay_ms));
        }
        RealmanFault::MalformedReply { count } => lock(&shared.wire).truncate_next = count,
        RealmanFault::UdpLoss { permille } => {
            if permille > 1000 {
                return Err(FaultError::BadProbability { permille });
            }
            lock(&shared.push_faults).loss_permille = permille;
        }
        RealmanFault::UdpReorder => lock(&shared.push_faults).reorder = true,
        ref other => {
            lock(&shared.core).inject(other)?;
            route_events(shared);
        }
    }
    Ok(())
}

/// Remove a fault of `kind` from the transport or the controller.
fn clear_fault(shared: &Shared, kind: RealmanFaultKind) {
    match kind {
        RealmanFaultKind::ConnectionDrop => {}
        RealmanFaultKind::ReplyDelay => lock(&shared.wire).reply_delay = None,
        RealmanFaultKind::MalformedReply => lock(&shared.wire).truncate_next = 0,
        RealmanFaultKind::UdpLoss => lock(&shared.push_faults).loss_permille = 0,
        RealmanFaultKind::UdpReorder => lock(&shared.push_faults).reorder = false,
        other => lock(&shared.core).clear(other),
    }
}

/// A shared view of a running emulator, from [`RealmanHandle::monitor`].
#[derive(Clone)]
pub struct RealmanMonitor {
    shared: Arc<Shared>,
}

impl std::fmt::Debug for RealmanMonitor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RealmanMonitor").finish_non_exhaustive()
    }
}

impl RealmanMonitor {
    /// See [`RealmanHandle::inject`].
    pub fn inject(&self, fault: RealmanFault) -> Result<(), FaultError> {
        inject_fault(&self.shared, fault)
    }

    /// See [`RealmanHandle::clear`].
    pub fn clear(&self, kind: RealmanFaultKind) {
        clear_fault(&self.shared, kind);
    }

    /// See [`RealmanHandle::snapshot`].
    pub fn snapshot(&self) -> ArmSnapshot {
        lock(&self.shared.core).snapshot()
    }

    /// See [`RealmanHandle::with_controller`].
    pub fn with_controller<R>(&self, f: impl FnOnce(&mut Controller) -> R) -> R {
        f(&mut lock(&self.shared.core))
    }

    /// Where the UDP push goes now: none while it is off or no client is connected, on a
    /// public bind only a connected client's address (the push task asks the same question).
    pub fn push_targets(&self) -> Vec<SocketAddr> {
        let push = lock(&self.shared.core).params().push.clone();
        push_targets(&self.shared, &push)
    }

    /// Peer addresses of the TCP clients connected now.
    pub fn clients(&self) -> Vec<SocketAddr> {
        lock(&self.shared.clients)
            .values()
            .map(|c| c.peer)
            .collect()
    }

    /// See [`RealmanHandle::stats`].
    pub fn stats(&self) -> ServerStats {
        *lock(&self.shared.stats)
    }
}

/// Starts Realman emulators. See [`RealmanEmulator::spawn`].
#[derive(Debug, Clone, Copy)]
pub struct RealmanEmulator;

/// A running emulator. Dropping it stops its tasks; [`RealmanHandle::shutdown`] also waits.
pub struct RealmanHandle {
    shared: Arc<Shared>,
    local_addr: Option<SocketAddr>,
    datagrams: Mutex<Option<mpsc::UnboundedReceiver<Datagram>>>,
    stop: watch::Sender<bool>,
    tasks: Vec<JoinHandle<()>>,
    state_file: bool,
    death: DeathWatch,
}

impl std::fmt::Debug for RealmanHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RealmanHandle")
            .field("local_addr", &self.local_addr)
            .finish()
    }
}

impl RealmanEmulator {
    /// Boot a controller and start serving on `transport` (on the current tokio runtime:
    /// paused clock = virtual time with [`Transport::InMemory`], multi-thread = real time).
    pub async fn spawn(
        config: EmulatorConfig,
        transport: Transport,
    ) -> Result<RealmanHandle, ServerError> {
        let runtime = tokio::runtime::Handle::try_current().map_err(|_| ServerError::NoRuntime)?;
        let state_file = config.controller.state_file.is_some();
        let controller = Controller::new(config.controller)?;
        let (stop, stop_rx) = watch::channel(false);
        let shared = Arc::new(Shared {
            core: Mutex::new(controller),
            clients: Mutex::new(BTreeMap::new()),
            wire: Mutex::new(WireFaults::default()),
            push_faults: Mutex::new(PushFaults::new(config.seed)),
            stats: Mutex::new(ServerStats::default()),
            next_client: AtomicU64::new(1),
            max_connections: config.max_connections.max(1),
            idle_timeout: config.idle_timeout,
            epoch: Instant::now(),
            stop: stop_rx,
            public: matches!(transport, Transport::Tcp(addr) if !addr.ip().is_loopback()),
        });
        let mut tasks = Vec::new();
        let (sink, local_addr, datagrams) = match transport {
            Transport::Tcp(addr) => {
                let listener = TcpListener::bind(addr)
                    .await
                    .map_err(|source| ServerError::Bind { addr, source })?;
                let bound = listener
                    .local_addr()
                    .map_err(|source| ServerError::Bind { addr, source })?;
                // Push from the command port's number, so that a client receiving several
                // controllers on one UDP port can tell them apart by source address (two
                // emulators on one host share the IP). If that UDP port is taken, any port.
                let same_port = SocketAddr::new(bound.ip(), bound.port());
                let udp = match UdpSocket::bind(same_port).await {
                    Ok(udp) => udp,
                    Err(_) => {
                        let udp_addr = SocketAddr::new(bound.ip(), 0);
                        UdpSocket::bind(udp_addr)
                            .await
                            .map_err(|source| ServerError::Bind {
                                addr: udp_addr,
                                source,
                            })?
                    }
                };
                tasks.push(runtime.spawn(accept_loop(Arc::clone(&shared), listener)));
                (PushSink::Udp(udp), Some(bound), None)
            }
            Transport::InMemory => {
                let (tx, rx) = mpsc::unbounded_channel();
                (PushSink::Channel(tx), None, Some(rx))
            }
        };
        let ticks = u64::from(config.ticks_per_wake.clamp(1, 10));
        // A panic in the core is reported on the death watch, not left behind an open port.
        let (supervisor, death) = Supervisor::new();
        let core = core_loop(Arc::clone(&shared), sink, ticks);
        tasks.push(supervisor.spawn(&runtime, "Realman core", async move {
            core.await;
            Ok(())
        }));
        Ok(RealmanHandle {
            shared,
            local_addr,
            datagrams: Mutex::new(datagrams),
            stop,
            tasks,
            state_file,
            death,
        })
    }
}

impl RealmanHandle {
    /// The TCP address it listens on (`None` in memory).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local_addr
    }

    /// Open an in-memory connection as a client at `peer_ip` would (the push aims at that IP).
    /// Over the connection cap the stream is closed at once, as a TCP connection would be.
    pub fn connect(&self, peer_ip: IpAddr) -> Result<DuplexStream, ServerError> {
        if let Some(addr) = self.local_addr {
            return Err(ServerError::NotInMemory { addr });
        }
        let (client, server) = tokio::io::duplex(DUPLEX_BYTES);
        let port = 40_000 + (self.shared.next_client.load(Ordering::Relaxed) % 20_000) as u16;
        tokio::spawn(serve_connection(
            Arc::clone(&self.shared),
            server,
            SocketAddr::new(peer_ip, port),
        ));
        Ok(client)
    }

    /// The in-memory datagram stream (once; `None` on TCP or the second call).
    pub fn take_datagrams(&self) -> Option<mpsc::UnboundedReceiver<Datagram>> {
        lock(&self.datagrams).take()
    }

    /// Inject a fault.
    pub fn inject(&self, fault: RealmanFault) -> Result<(), FaultError> {
        inject_fault(&self.shared, fault)
    }

    /// Remove a fault.
    pub fn clear(&self, kind: RealmanFaultKind) {
        clear_fault(&self.shared, kind);
    }

    /// A cloneable view of this emulator for monitors (the web view of `armhil sim --ui`):
    /// snapshot, faults and the connected clients, shareable between tasks.
    pub fn monitor(&self) -> RealmanMonitor {
        RealmanMonitor {
            shared: Arc::clone(&self.shared),
        }
    }

    /// The simulation's ground truth now.
    pub fn snapshot(&self) -> ArmSnapshot {
        lock(&self.shared.core).snapshot()
    }

    /// Run `f` on the controller (tests, harness observations).
    pub fn with_controller<R>(&self, f: impl FnOnce(&mut Controller) -> R) -> R {
        f(&mut lock(&self.shared.core))
    }

    /// Connections open now.
    pub fn connections(&self) -> usize {
        lock(&self.shared.clients).len()
    }

    /// Transport counters.
    pub fn stats(&self) -> ServerStats {
        *lock(&self.shared.stats)
    }

    /// A watch that tells when the emulator stops serving on its own (its core task
    /// panicked); `armhil sim` exits non-zero on it.
    pub fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Stop serving (closing every connection), save the state file if one is configured,
    /// and wait for the tasks. A state file that cannot be written is logged; see
    /// [`RealmanHandle::shutdown_and_save`] to get the error.
    pub async fn shutdown(self) {
        if let Err(e) = self.shutdown_and_save().await {
            tracing::warn!(error = %e, "Realman emulator cannot save its state file");
        }
    }

    /// [`RealmanHandle::shutdown`], returning why the state file could not be written.
    pub async fn shutdown_and_save(mut self) -> Result<(), StateFileError> {
        let _ = self.stop.send(true);
        for task in self.tasks.drain(..) {
            let _ = task.await;
        }
        if self.state_file {
            lock(&self.shared.core).save_state()?;
        }
        Ok(())
    }
}

impl Drop for RealmanHandle {
    fn drop(&mut self) {
        let _ = self.stop.send(true);
    }
}

async fn accept_loop(shared: Arc<Shared>, listener: TcpListener) {
    let mut stop = shared.stop.clone();
    let mut accept_failures: u64 = 0;
    loop {
        let accepted = tokio::select! {
            r = listener.accept() => r,
            _ = stop.changed() => break,
        };
        match accepted {
            Ok((stream, peer)) => {
                // Each reply and event is its own segment, as on the controller.
                let _ = stream.set_nodelay(true);
                tokio::spawn(serve_connection(Arc::clone(&shared), stream, peer));
            }
            Err(e) => {
                // Out of descriptors and the like: wait and keep listening. Logged at the 1st,
                // 2nd, 4th, … failure: at one try every 10 ms a warning each would flood the log.
                accept_failures += 1;
                if accept_failures.is_power_of_two() {
                    tracing::warn!(error = %e, failures = accept_failures, "Realman emulator accept failed");
                }
                sleep(Duration::from_millis(10)).await;
            }
        }
    }
}

/// What a connection's tasks get when it is admitted.
struct Admitted {
    id: ClientId,
    tx: mpsc::Sender<Outgoing>,
    rx: mpsc::Receiver<Outgoing>,
    kill: watch::Receiver<Option<&'static str>>,
    activity: Activity,
}

/// Admit a client, evicting the client idle longest if every slot is taken and it has been
/// idle for [`EVICT_IDLE_AFTER`], or refuse it.
fn admit(shared: &Shared, peer: SocketAddr) -> Option<Admitted> {
    let mut clients = lock(&shared.clients);
    // Clients being closed (evicted, dropped) no longer hold a slot.
    let live = clients.values().filter(|c| !c.ending()).count();
    if live >= shared.max_connections {
        let idlest = clients
            .values()
            .filter(|c| !c.ending())
            .min_by_key(|c| c.active_ms.load(Ordering::Relaxed));
        let idle_since = idlest
            .map(|c| shared.epoch + Duration::from_millis(c.active_ms.load(Ordering::Relaxed)));
        match (idlest, idle_since) {
            (Some(client), Some(since)) if since + EVICT_IDLE_AFTER <= Instant::now() => {
                tracing::info!(evicted = %client.peer, %peer, "Realman emulator full: the client idle longest gives its slot to a new one");
                client.end("evicted (idle while the emulator was full)");
                lock(&shared.stats).evicted += 1;
            }
            _ => {
                drop(clients);
                lock(&shared.stats).refused += 1;
                tracing::warn!(%peer, cap = shared.max_connections, "Realman emulator refused a connection: too many clients");
                return None;
            }
        }
    }
    let id = shared.next_client.fetch_add(1, Ordering::Relaxed);
    let (tx, rx) = mpsc::channel(CLIENT_QUEUE);
    let (kill, kill_rx) = watch::channel(None);
    let activity = Activity {
        epoch: shared.epoch,
        ms: Arc::new(AtomicU64::new(0)),
    };
    activity.touch();
    clients.insert(
        id,
        Client {
            peer,
            tx: tx.clone(),
            kill,
            active_ms: Arc::clone(&activity.ms),
        },
    );
    drop(clients);
    lock(&shared.stats).accepted += 1;
    tracing::info!(%peer, client = id, "Realman client connected");
    Some(Admitted {
        id,
        tx,
        rx,
        kill: kill_rx,
        activity,
    })
}

/// Serve one client until it disconnects, is dropped by a fault, or the emulator stops.
async fn serve_connection<S>(shared: Arc<Shared>, stream: S, peer: SocketAddr)
where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let Some(client) = admit(&shared, peer) else {
        drop(stream);
        return;
    };
    let id = client.id;
    let (reader, writer) = tokio::io::split(stream);
    let writer_task = tokio::spawn(write_loop(
        Arc::clone(&shared),
        writer,
        client.rx,
        client.kill.clone(),
        client.activity.clone(),
    ));
    let connection = Connection {
        shared: &shared,
        id,
        tx: client.tx,
        kill: client.kill,
        activity: client.activity,
    };
    let reason = connection.read_loop(reader).await;
    lock(&shared.clients).remove(&id);
    lock(&shared.core).disconnect(id);
    let _ = writer_task.await;
    tracing::info!(%peer, client = id, reason, "Realman client disconnected");
}

/// Why a wait inside the reader ended early.
enum Interrupted {
    /// The connection must end, for this reason.
    End(&'static str),
}

/// The reading side of one connection.
struct Connection<'a> {
    shared: &'a Shared,
    id: ClientId,
    tx: mpsc::Sender<Outgoing>,
    kill: watch::Receiver<Option<&'static str>>,
    activity: Activity,
}

impl Connection<'_> {
    /// Run `work` unless the connection is killed, the emulator stops or the connection has
    /// been idle (no byte either way) for the idle timeout.
    async fn guarded<T>(
        &mut self,
        work: impl std::future::Future<Output = T>,
    ) -> Result<T, Interrupted> {
        let mut stop = self.shared.stop.clone();
        tokio::pin!(work);
        loop {
            let idle_at = self
                .shared
                .idle_timeout
                .and_then(|t| self.activity.last().checked_add(t));
            let idle = async {
                match idle_at {
                    Some(at) => sleep_until(at).await,
                    None => std::future::pending().await,
                }
            };
            tokio::select! {
                out = &mut work => return Ok(out),
                _ = self.kill.changed() => {
                    let reason = (*self.kill.borrow()).unwrap_or("dropped");
                    return Err(Interrupted::End(reason));
                }
                _ = stop.changed() => return Err(Interrupted::End("emulator stopped")),
                _ = idle => {
                    // The writer may have been active meanwhile: look again.
                    let idle_until = self
                        .shared
                        .idle_timeout
                        .and_then(|t| self.activity.last().checked_add(t));
                    if idle_until.is_some_and(|at| at <= Instant::now()) {
                        lock(&self.shared.stats).idle_closed += 1;
                        return Err(Interrupted::End("idle timeout"));
                    }
                }
            }
        }
    }

    async fn read_loop<R: AsyncRead + Unpin>(mut self, mut reader: R) -> &'static str {
        let mut guard = HttpGuard::new();
        let mut splitter = Splitter::new(MAX_REQUEST_BYTES);
        let mut buf = vec![0u8; READ_CHUNK];
        let mut units = Vec::new();
        let id = self.id;
        loop {
            let n = match self.guarded(reader.read(&mut buf)).await {
                Ok(Ok(0)) => return "peer closed",
                Ok(Ok(n)) => n,
                Ok(Err(_)) => return "read error",
                Err(Interrupted::End(reason)) => return reason,
            };
            self.activity.touch();
            // The only way from the socket to the splitter: nothing of an HTTP request runs.
            let clean = match guard.admit(&buf[..n]) {
                Ok(clean) => clean,
                Err(refused) => {
                    lock(&self.shared.stats).http_refused += 1;
                    tracing::warn!(client = id, %refused, "Realman emulator closes a connection that speaks HTTP (a web page's request?)");
                    return "HTTP request";
                }
            };
            if let Err(e) = splitter.feed(clean, &mut units) {
                lock(&self.shared.stats).oversize += 1;
                tracing::warn!(client = id, error = %e, "Realman emulator closes a connection");
                return "request too long";
            }
            for unit in std::mem::take(&mut units) {
                let Unit::Object(bytes) = unit else {
                    handle_junk(self.shared, id, &unit);
                    continue;
                };
                // Take the request only while the queue has room for its reply and the
                // headroom for events; meanwhile this client is not read (D3: a client that
                // never reads its replies used to grow the process without bound).
                let tx = self.tx.clone();
                let permits = match self.guarded(tx.reserve_many(EVENT_HEADROOM + 1)).await {
                    Ok(Ok(permits)) => permits,
                    Ok(Err(_)) => return "writer stopped",
                    Err(Interrupted::End(reason)) => return reason,
                };
                let mut permits = permits;
                let Some(permit) = permits.next() else {
                    return "writer stopped";
                };
                drop(permits);
                handle_request(self.shared, id, &bytes, permit);
            }
        }
    }
}

fn handle_junk(shared: &Shared, id: ClientId, unit: &Unit) {
    lock(&shared.stats).malformed += 1;
    let len = match unit {
        Unit::Object(bytes) | Unit::Junk(bytes) => bytes.len(),
    };
    tracing::debug!(
        client = id,
        len,
        "Realman emulator ignores bytes outside a JSON object"
    );
}

/// Answer one request; its reply (if any) goes out through `permit`, reserved beforehand.
fn handle_request(shared: &Shared, id: ClientId, bytes: &[u8], permit: mpsc::Permit<'_, Outgoing>) {
    let request: serde_json::Value = match serde_json::from_slice(bytes) {
        Ok(v) => v,
        Err(e) => {
            lock(&shared.stats).malformed += 1;
            tracing::debug!(client = id, error = %e, "Realman emulator ignores malformed JSON");
            return;
        }
    };
    let answer = lock(&shared.core).handle(id, &request);
    match answer {
        Answer::Reply(text) => permit.send(Outgoing { text }),
        Answer::Silent => {}
        Answer::Unknown => {
            lock(&shared.stats).unknown += 1;
            let command = request.get("command").map(ToString::to_string);
            tracing::debug!(
                client = id,
                command,
                "Realman emulator ignores an unknown command"
            );
        }
    }
    // A command can end a move at once (disable, power off): its event follows the reply.
    route_events(shared);
}

/// Hand the controller's events to their clients' writers.
fn route_events(shared: &Shared) {
    let events = lock(&shared.core).take_events();
    if events.is_empty() {
        return;
    }
    let clients = lock(&shared.clients);
    for event in events {
        let Some(client) = clients.get(&event.to) else {
            continue;
        };
        match client.tx.try_send(Outgoing { text: event.text }) {
            Ok(()) | Err(mpsc::error::TrySendError::Closed(_)) => {}
            Err(mpsc::error::TrySendError::Full(_)) => {
                // The reader keeps EVENT_HEADROOM free: this client has not read for a while.
                if !client.ending() {
                    lock(&shared.stats).slow_dropped += 1;
                    tracing::warn!(peer = %client.peer, client = event.to, "Realman client dropped: it does not read (no room for an event)");
                }
                client.end("not reading (queue full)");
            }
        }
    }
}

async fn write_loop<W: AsyncWrite + Unpin>(
    shared: Arc<Shared>,
    mut writer: W,
    mut rx: mpsc::Receiver<Outgoing>,
    mut kill: watch::Receiver<Option<&'static str>>,
    activity: Activity,
) {
    loop {
        let msg = tokio::select! {
            m = rx.recv() => match m {
                Some(m) => m,
                None => break,
            },
            _ = kill.changed() => break,
        };
        let (delay, truncate) = {
            let mut wire = lock(&shared.wire);
            let truncate = wire.truncate_next > 0;
            if truncate {
                wire.truncate_next -= 1;
            }
            (wire.reply_delay, truncate)
        };
        if let Some(d) = delay {
            sleep(d).await;
        }
        let mut text = msg.text;
        if truncate {
            let mut cut = text.len() / 2;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text.truncate(cut);
        }
        text.push_str("\r\n");
        let written = async {
            writer.write_all(text.as_bytes()).await?;
            writer.flush().await
        };
        let written = tokio::select! {
            w = written => w,
            // A peer that does not read must not keep the writer (and the slot) for ever.
            _ = kill.changed() => break,
        };
        if written.is_err() {
            // The peer went away mid-reply; the reader notices and cleans up.
            break;
        }
        activity.touch();
    }
    let _ = writer.shutdown().await;
}

/// The 1 kHz core: physics steps locked to the (virtual or wall) clock, events routed, and the
/// push sent every `cycle` × 5 ms. After a late wake-up the missed steps run at once and their
/// push periods are coalesced into one datagram.
async fn core_loop(shared: Arc<Shared>, sink: PushSink, ticks_per_wake: u64) {
    let mut stop = shared.stop.clone();
    let start = Instant::now();
    let period = Duration::from_millis(ticks_per_wake);
    let mut done: u64 = 0;
    let mut next = start + period;
    let mut push_stats = PushStats::default();
    loop {
        tokio::select! {
            _ = sleep_until(next) => {}
            _ = stop.changed() => break,
        }
        let due = (Instant::now() - start).as_millis() as u64;
        let behind = due.saturating_sub(done);
        if behind > ticks_per_wake + OVERRUN_SLACK_MS {
            lock(&shared.stats).overruns += 1;
        }
        let run = behind.min(MAX_CATCH_UP_TICKS);
        let mut push_due = false;
        {
            let mut core = lock(&shared.core);
            let cycle_ms = u64::from(core.params().push.cycle.max(1)) * 5;
            for _ in 0..run {
                core.tick();
                done += 1;
                push_due |= done.is_multiple_of(cycle_ms);
            }
        }
        // Skip what could not be caught up rather than bursting it later.
        done = done.max(due.saturating_sub(MAX_CATCH_UP_TICKS));
        route_events(&shared);
        if push_due {
            send_push(&shared, &sink, &mut push_stats).await;
        }
        next += period;
        if next < Instant::now() {
            next = Instant::now() + period;
        }
    }
}

/// Where the push goes now (see [`push::targets`]): the one answer the push task and the
/// monitor (the web view) share, so a view never lists an address the push has stopped
/// going to.
fn push_targets(shared: &Shared, push: &PushConfig) -> Vec<SocketAddr> {
    if !push.enable {
        return Vec::new();
    }
    let clients: Vec<SocketAddr> = lock(&shared.clients).values().map(|c| c.peer).collect();
    push::targets(&push.ip, push.port, &clients, shared.public)
}

async fn send_push(shared: &Shared, sink: &PushSink, stats: &mut PushStats) {
    let (payload, push) = {
        let core = lock(&shared.core);
        let push = core.params().push.clone();
        if !push.enable {
            return;
        }
        (core.push_datagram(), push)
    };
    for to in push_targets(shared, &push) {
        let out = lock(&shared.push_faults).apply(Datagram {
            to,
            payload: payload.clone(),
        });
        for datagram in out {
            sink.send(datagram, stats).await;
        }
    }
    lock(&shared.stats).push = *stats;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::realman::model::ArmModel;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    use tokio::time::timeout;

    const PEER: IpAddr = IpAddr::V4(std::net::Ipv4Addr::new(192, 168, 1, 10));
    const POWER_OFF: &str = r#"{"command":"set_arm_power","arm_power":0}"#;

    async fn emulator(tune: impl FnOnce(&mut EmulatorConfig)) -> RealmanHandle {
        let mut config = EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b()));
        tune(&mut config);
        RealmanEmulator::spawn(config, Transport::InMemory)
            .await
            .expect("emulator boots")
    }

    /// Read until the server closes the stream; `None` if it stays open for `within`.
    async fn closed_within(stream: &mut DuplexStream, within: Duration) -> Option<Vec<u8>> {
        let mut seen = Vec::new();
        timeout(within, stream.read_to_end(&mut seen))
            .await
            .ok()?
            .ok()?;
        Some(seen)
    }

    /// One reply line (CRLF-terminated) within `within`.
    async fn reply(stream: &mut DuplexStream, within: Duration) -> Option<String> {
        let mut line = Vec::new();
        let mut byte = [0u8; 1];
        timeout(within, async {
            while !line.ends_with(b"\r\n") {
                match stream.read(&mut byte).await {
                    Ok(1) => line.push(byte[0]),
                    _ => return None,
                }
            }
            Some(String::from_utf8_lossy(&line).into_owned())
        })
        .await
        .ok()?
    }

    #[tokio::test(start_paused = true)]
    async fn a_browser_post_is_closed_and_does_not_power_the_arm_off() {
        let emu = emulator(|_| {}).await;
        assert!(emu.snapshot().power_on);
        let request = format!(
            "POST / HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nOrigin: https://attacker.example\r\n\
             Content-Type: text/plain;charset=UTF-8\r\nContent-Length: {}\r\n\r\n{POWER_OFF}",
            POWER_OFF.len()
        );
        for piece in [request.len(), 3] {
            let mut stream = emu.connect(PEER).unwrap();
            for part in request.as_bytes().chunks(piece) {
                if stream.write_all(part).await.is_err() {
                    break;
                }
            }
            let seen = closed_within(&mut stream, Duration::from_secs(2)).await;
            assert_eq!(seen.as_deref(), Some(&b""[..]), "closed without a reply");
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
        assert!(emu.snapshot().power_on, "the page powered the arm off");
        assert_eq!(emu.stats().http_refused, 2);

        // The body alone, from a JSON client, does power it off (so the test can fail).
        let mut stream = emu.connect(PEER).unwrap();
        stream.write_all(POWER_OFF.as_bytes()).await.unwrap();
        assert!(reply(&mut stream, Duration::from_secs(2)).await.is_some());
        assert!(!emu.snapshot().power_on);
    }

    #[tokio::test(start_paused = true)]
    async fn a_client_that_does_not_read_is_not_read_either() {
        let emu = emulator(|c| c.idle_timeout = Some(Duration::from_secs(600))).await;
        let mut stream = emu.connect(PEER).unwrap();
        let request = b"{\"command\":\"get_joint_degree\"}\r\n";
        let total = 8 << 20;
        let many = request.repeat(total / request.len());
        // Without the bound the server reads (and queues replies to) all 8 MiB.
        let wrote = timeout(Duration::from_secs(3), stream.write_all(&many)).await;
        assert!(
            wrote.is_err(),
            "the server kept reading a client that reads nothing"
        );
        assert_eq!(
            emu.connections(),
            1,
            "a client that only sends is not dropped"
        );
        // Once it reads, it gets its replies and the server reads again.
        let (mut read, mut write) = tokio::io::split(stream);
        let drain = tokio::spawn(async move {
            let mut buf = vec![0u8; 64 * 1024];
            let mut lines = 0usize;
            while lines < 1000 {
                match read.read(&mut buf).await {
                    Ok(0) | Err(_) => break,
                    Ok(n) => lines += buf[..n].iter().filter(|&&b| b == b'\n').count(),
                }
            }
            lines
        });
        write.write_all(request).await.unwrap();
        let lines = timeout(Duration::from_secs(10), drain)
            .await
            .unwrap()
            .unwrap();
        assert!(lines >= 1000, "{lines} replies");
    }

    #[tokio::test(start_paused = true)]
    async fn an_idle_connection_is_closed_and_a_busy_one_is_not() {
        let emu = emulator(|c| c.idle_timeout = Some(Duration::from_secs(2))).await;
        let mut idle = emu.connect(PEER).unwrap();
        let mut busy = emu.connect(PEER).unwrap();
        for _ in 0..5 {
            busy.write_all(b"{\"command\":\"get_arm_power_state\"}")
                .await
                .unwrap();
            assert!(reply(&mut busy, Duration::from_secs(1)).await.is_some());
            tokio::time::sleep(Duration::from_millis(900)).await;
        }
        assert!(closed_within(&mut idle, Duration::from_millis(100))
            .await
            .is_some());
        assert_eq!(emu.connections(), 1);
        assert_eq!(emu.stats().idle_closed, 1);
    }

    #[tokio::test(start_paused = true)]
    async fn at_the_cap_a_newcomer_takes_the_slot_of_a_long_idle_client() {
        let emu = emulator(|c| {
            c.max_connections = 2;
            c.idle_timeout = None;
        })
        .await;
        let mut first = emu.connect(PEER).unwrap();
        tokio::time::sleep(Duration::from_secs(1)).await;
        let mut second = emu.connect(PEER).unwrap();
        // Nobody has been idle for EVICT_IDLE_AFTER yet: refused.
        let mut refused = emu.connect(PEER).unwrap();
        let seen = closed_within(&mut refused, Duration::from_millis(100)).await;
        assert_eq!(seen.as_deref(), Some(&b""[..]));
        assert_eq!(emu.stats().refused, 1);

        tokio::time::sleep(EVICT_IDLE_AFTER).await;
        second
            .write_all(b"{\"command\":\"get_arm_power_state\"}")
            .await
            .unwrap();
        assert!(reply(&mut second, Duration::from_secs(1)).await.is_some());
        let mut newcomer = emu.connect(PEER).unwrap();
        newcomer
            .write_all(b"{\"command\":\"get_arm_power_state\"}")
            .await
            .unwrap();
        assert!(reply(&mut newcomer, Duration::from_secs(1)).await.is_some());
        // The idlest one (the first) made room; the second, just active, stays.
        assert!(closed_within(&mut first, Duration::from_millis(100))
            .await
            .is_some());
        assert_eq!(emu.stats().evicted, 1);
        assert_eq!(emu.connections(), 2);
    }

    #[tokio::test(start_paused = true)]
    async fn the_push_stops_when_the_last_client_leaves() {
        let emu = emulator(|_| {}).await;
        let mut datagrams = emu.take_datagrams().unwrap();
        let mut stream = emu.connect(PEER).unwrap();
        let set = r#"{"command":"set_realtime_push","ip":"10.0.0.7","port":9000}"#;
        stream.write_all(set.as_bytes()).await.unwrap();
        assert!(reply(&mut stream, Duration::from_secs(2)).await.is_some());
        tokio::time::sleep(Duration::from_millis(100)).await;
        let mut seen = 0;
        while datagrams.try_recv().is_ok() {
            seen += 1;
        }
        assert!(seen > 10, "{seen} datagrams while a client is connected");
        // D7: with no client left, the stored target gets nothing.
        drop(stream);
        tokio::time::sleep(Duration::from_millis(50)).await;
        while datagrams.try_recv().is_ok() {}
        tokio::time::sleep(Duration::from_millis(500)).await;
        assert!(
            datagrams.try_recv().is_err(),
            "pushed with no client connected"
        );
        assert_eq!(emu.connections(), 0);
    }
}
