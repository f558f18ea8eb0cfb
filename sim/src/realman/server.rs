//! The emulator's transport: a TCP listener (real time) or in-memory duplex streams (virtual
//! time) feeding one [`Controller`], a 1 kHz core task, and the UDP realtime push.
//!
//! Every connection runs the same generic code over `AsyncRead + AsyncWrite`: a reader that
//! splits requests ([`Splitter`]), answers them under the controller lock and queues the reply,
//! and a writer that writes each queued message (reply or event) as its own write (compact JSON
//! and CRLF). Replies and events share the client's queue, so an acknowledgement always
//! precedes the arrival event of its move and the two never share a write.

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
use super::push::{Datagram, PushFaults, PushSink, PushStats};

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
}

impl EmulatorConfig {
    /// Defaults around a controller configuration.
    pub fn new(controller: ControllerConfig) -> Self {
        Self {
            controller,
            max_connections: DEFAULT_MAX_CONNECTIONS,
            ticks_per_wake: 1,
            seed: 0,
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
    tx: mpsc::UnboundedSender<Outgoing>,
    kill: watch::Sender<bool>,
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
    stop: watch::Receiver<bool>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while holding a lock must not take the whole emulator down with it.
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Apply `fault` to the transport or the controller.
fn inject_fault(shared: &Shared, fault: RealmanFault) -> Result<(), FaultError> {
    tracing::info!(fault = fault.name(), "Realman fault injected");
    match fault {
        RealmanFault::ConnectionDrop { peer_ip } => {
            for client in lock(&shared.clients).values() {
                if peer_ip.is_none_or(|ip| ip == client.peer.ip()) {
                    let _ = client.kill.send(true);
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
            stop: stop_rx,
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
                let udp_addr = SocketAddr::new(bound.ip(), 0);
                let udp = UdpSocket::bind(udp_addr)
                    .await
                    .map_err(|source| ServerError::Bind {
                        addr: udp_addr,
                        source,
                    })?;
                tasks.push(runtime.spawn(accept_loop(Arc::clone(&shared), listener)));
                (PushSink::Udp(udp), Some(bound), None)
            }
            Transport::InMemory => {
                let (tx, rx) = mpsc::unbounded_channel();
                (PushSink::Channel(tx), None, Some(rx))
            }
        };
        let ticks = u64::from(config.ticks_per_wake.clamp(1, 10));
        tasks.push(runtime.spawn(core_loop(Arc::clone(&shared), sink, ticks)));
        Ok(RealmanHandle {
            shared,
            local_addr,
            datagrams: Mutex::new(datagrams),
            stop,
            tasks,
            state_file,
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

    /// Stop serving (closing every connection), save the state file if one is configured,
    /// and wait for the tasks.
    pub async fn shutdown(mut self) {
        let _ = self.stop.send(true);
        for task in self.tasks.drain(..) {
            let _ = task.await;
        }
        if self.state_file {
            if let Err(e) = lock(&self.shared.core).save_state() {
                tracing::warn!(error = %e, "Realman emulator cannot save its state file");
            }
        }
    }
}

impl Drop for RealmanHandle {
    fn drop(&mut self) {
        let _ = self.stop.send(true);
    }
}

async fn accept_loop(shared: Arc<Shared>, listener: TcpListener) {
    let mut stop = shared.stop.clone();
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
                // Out of descriptors and the like: wait and keep listening.
                tracing::warn!(error = %e, "Realman emulator accept failed");
                sleep(Duration::from_millis(10)).await;
            }
        }
    }
}

/// Admit a client or refuse it (cap reached).
fn admit(
    shared: &Shared,
    peer: SocketAddr,
) -> Option<(
    ClientId,
    mpsc::UnboundedReceiver<Outgoing>,
    watch::Receiver<bool>,
)> {
    let mut clients = lock(&shared.clients);
    if clients.len() >= shared.max_connections {
        drop(clients);
        lock(&shared.stats).refused += 1;
        tracing::warn!(%peer, cap = shared.max_connections, "Realman emulator refused a connection: too many clients");
        return None;
    }
    let id = shared.next_client.fetch_add(1, Ordering::Relaxed);
    let (tx, rx) = mpsc::unbounded_channel();
    let (kill, kill_rx) = watch::channel(false);
    clients.insert(id, Client { peer, tx, kill });
    drop(clients);
    lock(&shared.stats).accepted += 1;
    tracing::info!(%peer, client = id, "Realman client connected");
    Some((id, rx, kill_rx))
}

/// Serve one client until it disconnects, is dropped by a fault, or the emulator stops.
async fn serve_connection<S>(shared: Arc<Shared>, stream: S, peer: SocketAddr)
where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let Some((id, rx, kill)) = admit(&shared, peer) else {
        drop(stream);
        return;
    };
    let (reader, writer) = tokio::io::split(stream);
    let writer_task = tokio::spawn(write_loop(Arc::clone(&shared), writer, rx, kill.clone()));
    let reason = read_loop(&shared, id, reader, kill).await;
    lock(&shared.clients).remove(&id);
    lock(&shared.core).disconnect(id);
    let _ = writer_task.await;
    tracing::info!(%peer, client = id, reason, "Realman client disconnected");
}

async fn read_loop<R: AsyncRead + Unpin>(
    shared: &Shared,
    id: ClientId,
    mut reader: R,
    mut kill: watch::Receiver<bool>,
) -> &'static str {
    let mut stop = shared.stop.clone();
    let mut splitter = Splitter::new(MAX_REQUEST_BYTES);
    let mut buf = vec![0u8; READ_CHUNK];
    let mut units = Vec::new();
    loop {
        let n = tokio::select! {
            r = reader.read(&mut buf) => match r {
                Ok(0) => return "peer closed",
                Ok(n) => n,
                Err(_) => return "read error",
            },
            _ = kill.changed() => return "dropped by fault",
            _ = stop.changed() => return "emulator stopped",
        };
        if let Err(e) = splitter.feed(&buf[..n], &mut units) {
            lock(&shared.stats).oversize += 1;
            tracing::warn!(client = id, error = %e, "Realman emulator closes a connection");
            return "request too long";
        }
        for unit in units.drain(..) {
            handle_unit(shared, id, unit);
        }
    }
}

fn handle_unit(shared: &Shared, id: ClientId, unit: Unit) {
    let bytes = match unit {
        Unit::Object(bytes) => bytes,
        Unit::Junk(bytes) => {
            lock(&shared.stats).malformed += 1;
            tracing::debug!(
                client = id,
                len = bytes.len(),
                "Realman emulator ignores bytes outside a JSON object"
            );
            return;
        }
    };
    let request: serde_json::Value = match serde_json::from_slice(&bytes) {
        Ok(v) => v,
        Err(e) => {
            lock(&shared.stats).malformed += 1;
            tracing::debug!(client = id, error = %e, "Realman emulator ignores malformed JSON");
            return;
        }
    };
    let answer = lock(&shared.core).handle(id, &request);
    match answer {
        Answer::Reply(text) => send_to(shared, id, text),
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

fn send_to(shared: &Shared, id: ClientId, text: String) {
    if let Some(client) = lock(&shared.clients).get(&id) {
        let _ = client.tx.send(Outgoing { text });
    }
}

/// Hand the controller's events to their clients' writers.
fn route_events(shared: &Shared) {
    let events = lock(&shared.core).take_events();
    if events.is_empty() {
        return;
    }
    let clients = lock(&shared.clients);
    for event in events {
        if let Some(client) = clients.get(&event.to) {
            let _ = client.tx.send(Outgoing { text: event.text });
        }
    }
}

async fn write_loop<W: AsyncWrite + Unpin>(
    shared: Arc<Shared>,
    mut writer: W,
    mut rx: mpsc::UnboundedReceiver<Outgoing>,
    mut kill: watch::Receiver<bool>,
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
        if written.await.is_err() {
            // The peer went away mid-reply; the reader notices and cleans up.
            break;
        }
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

async fn send_push(shared: &Shared, sink: &PushSink, stats: &mut PushStats) {
    let (payload, push) = {
        let core = lock(&shared.core);
        let push = core.params().push.clone();
        if !push.enable {
            return;
        }
        (core.push_datagram(), push)
    };
    let targets: Vec<SocketAddr> = match push.ip.parse::<IpAddr>() {
        Ok(ip) => vec![SocketAddr::new(ip, push.port)],
        Err(_) => {
            // No address set: every host holding a TCP connection, once per host.
            let mut ips: Vec<IpAddr> = lock(&shared.clients)
                .values()
                .map(|c| c.peer.ip())
                .collect();
            ips.sort_unstable();
            ips.dedup();
            ips.into_iter()
                .map(|ip| SocketAddr::new(ip, push.port))
                .collect()
        }
    };
    for to in targets {
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
