//! The socketcand server: one virtual bus, any number of TCP clients.
//!
//! Each connection runs as one task made of three parts that end it when any of them ends:
//! the reader (commands from the client), the forwarder (frames from the bus to the client)
//! and the writer (everything queued for the client, to the socket). The queue between them
//! is bounded; when a client does not read, frames for it are dropped and counted, the way a
//! SocketCAN socket whose receive queue is full drops frames. The connection itself stays: a
//! client may only ever send (piper_sdk opens a second connection it never reads), and its
//! commands must still reach the bus. Nothing a client does can hold up the bus or the other
//! clients; a client that sends faster than the bus carries frames is slowed through TCP.
//! Drops are logged as one summary a second per connection and kind, never one line per
//! drop (a client flooding bad input without reading used to turn 3 MB into 58 MB of log).
//!
//! Like a raw socket of a real socketcand, a client in raw mode receives every frame that
//! completes on the bus after its `< rawmode >`: frames of the grace period (see
//! [`ServerConfig::rawmode_grace`]) are held back, not discarded. And what a client sent
//! before it closed still reaches the bus (the rest of its input is read and its transmit
//! queue emptied before its node leaves): a send-and-exit tool loses none of its frames.
//!
//! Every byte a client sends passes the [`HttpGuard`] before the framer sees it: a connection
//! that opens with an HTTP request line or carries `Host:`/`Origin:` lines (a web page's
//! `fetch` to this port) is closed with nothing in it acted on. At most
//! [`ServerConfig::max_clients`] clients are served at once; further connections are closed
//! at once, so a connection storm cannot use up the process's file descriptors.

use std::collections::VecDeque;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinSet;
use tokio::time::Instant;

use super::http_guard::HttpGuard;
use super::log_limit::DropSummary;
use super::protocol::{self, Command, Element, Framer, Reply};
use crate::virtual_bus::{NodeOptions, VirtualBus, VirtualNode};
use crate::{BusError, CanBus, CanFrame};

/// How the server treats its clients.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServerConfig {
    /// Messages queued for one client before frames for it are dropped (default 4096, about
    /// a second of a busy 1 Mbit/s bus).
    pub client_queue: usize,
    /// Transmit queue of each client's node on the bus (default 64 frames).
    pub node_tx_queue: usize,
    /// How long a `send` waits for room in that queue before the client gets an error
    /// (default 1 s); meanwhile no further commands of that client are read.
    pub send_wait: Duration,
    /// Frames are written to a client only this long after `< ok >` answers `< rawmode >`
    /// (default 100 ms), or from the client's next command on, or from the `< rawmode >` of
    /// a later connection from the same address, whichever comes first: python-can reads
    /// that `< ok >` with one `recv` and compares it whole, so a frame arriving in the same
    /// read would fail its handshake. A client that sends a command, or has opened its next
    /// connection, has read its `< ok >`. Frames that complete on the bus meanwhile are held
    /// (up to [`ServerConfig::client_queue`]) and written when the grace ends, so the client
    /// misses none of them: piper_sdk reads on one connection and asks for the firmware
    /// version on a second one right after opening it, and the answer must reach the first.
    pub rawmode_grace: Duration,
    /// Kernel send buffer of each connection in bytes (default 64 KiB, some 1400 frames):
    /// bounds how stale the frames a lagging client reads can be before drops begin.
    pub send_buffer: usize,
    /// Most clients served at once (default 128); a further connection is closed as soon as
    /// it is accepted. Each client is a node on the bus and costs every other client some of
    /// its share of the bus's fan-out, and a descriptor of the process's limited supply.
    pub max_clients: usize,
}

/// Default of [`ServerConfig::max_clients`].
pub const DEFAULT_MAX_CLIENTS: usize = 128;

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            client_queue: 4096,
            node_tx_queue: 64,
            send_wait: Duration::from_secs(1),
            rawmode_grace: Duration::from_millis(100),
            send_buffer: 64 * 1024,
            max_clients: DEFAULT_MAX_CLIENTS,
        }
    }
}

/// Why the server could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// The listening socket could not be bound.
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

/// Counters of a running server.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ServerStats {
    /// Clients connected now.
    pub clients: usize,
    /// Connections accepted since the start.
    pub connections: u64,
    /// Frames clients put on the bus.
    pub frames_from_clients: u64,
    /// Frames queued to clients.
    pub frames_to_clients: u64,
    /// Frames not delivered because a client's queue was full.
    pub frames_dropped: u64,
    /// Elements answered with `< error … >`.
    pub errors: u64,
    /// Connections closed at once because [`ServerConfig::max_clients`] were connected.
    pub refused: u64,
    /// Connections closed because they carried HTTP (see [`HttpGuard`]).
    pub http_refused: u64,
    /// CAN FD frames not written to clients in raw mode: the protocol carries classic frames
    /// only (see [`super::protocol`]). The first is logged, once per server.
    pub fd_frames_not_forwarded: u64,
}

#[derive(Debug, Default)]
struct Counters {
    clients: AtomicUsize,
    connections: AtomicU64,
    frames_from_clients: AtomicU64,
    frames_to_clients: AtomicU64,
    frames_dropped: AtomicU64,
    errors: AtomicU64,
    refused: AtomicU64,
    http_refused: AtomicU64,
    fd_frames_not_forwarded: AtomicU64,
}

impl Counters {
    fn snapshot(&self) -> ServerStats {
        ServerStats {
            clients: self.clients.load(Ordering::Relaxed),
            connections: self.connections.load(Ordering::Relaxed),
            frames_from_clients: self.frames_from_clients.load(Ordering::Relaxed),
            frames_to_clients: self.frames_to_clients.load(Ordering::Relaxed),
            frames_dropped: self.frames_dropped.load(Ordering::Relaxed),
            errors: self.errors.load(Ordering::Relaxed),
            refused: self.refused.load(Ordering::Relaxed),
            http_refused: self.http_refused.load(Ordering::Relaxed),
            fd_frames_not_forwarded: self.fd_frames_not_forwarded.load(Ordering::Relaxed),
        }
    }
}

/// What every connection task shares.
struct Shared {
    channels: Channels,
    config: ServerConfig,
    counters: Counters,
    /// Numbers connections in the order they were accepted.
    next_connection: AtomicU64,
    /// Every live connection's raw-mode state, for [`Session::end_earlier_graces`].
    graces: Mutex<Vec<GraceEntry>>,
}

/// One connection in [`Shared::graces`].
struct GraceEntry {
    /// Its number in accept order.
    id: u64,
    /// The client's address (without the port: one client opens several connections).
    ip: IpAddr,
    /// Its raw-mode state; gone with the connection.
    raw: Weak<watch::Sender<Option<Instant>>>,
}

/// Start forwarding on a connection now if its raw mode is still in its grace period.
fn end_grace(raw: &watch::Sender<Option<Instant>>) {
    let now = Instant::now();
    raw.send_if_modified(|raw| match raw {
        Some(start) if *start > now => {
            *raw = Some(now);
            true
        }
        _ => false,
    });
}

/// The buses a server offers.
enum Channels {
    /// One bus, whatever name a client opens (a single-bus emulator).
    Any(VirtualBus),
    /// A bus per name (a robot's `can0` … `can3`): `< open can2 >` reaches `can2` only.
    Named(Vec<(String, VirtualBus)>),
}

impl Channels {
    /// The bus a client's `< open NAME >` reaches, or the reply refusing it.
    fn open(&self, name: &str) -> Result<&VirtualBus, String> {
        match self {
            Self::Any(bus) => Ok(bus),
            Self::Named(buses) => buses
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, bus)| bus)
                .ok_or_else(|| {
                    let names: Vec<&str> = buses.iter().map(|(n, _)| n.as_str()).collect();
                    format!("no bus {name} here; this server has {}", names.join(" "))
                }),
        }
    }
}

/// A running socketcand server. Dropping it (or [`SocketcandServer::shutdown`]) stops
/// accepting and closes every connection.
#[derive(Debug)]
pub struct SocketcandServer {
    local_addr: SocketAddr,
    shared: Arc<SharedHandle>,
    stop: watch::Sender<bool>,
    task: Option<tokio::task::JoinHandle<()>>,
}

/// `Shared` behind a Debug-friendly handle.
struct SharedHandle(Arc<Shared>);

impl std::fmt::Debug for SharedHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shared")
            .field("config", &self.0.config)
            .finish_non_exhaustive()
    }
}

impl SocketcandServer {
    /// Listen on `addr` (e.g. `127.0.0.1:29536`) and serve `bus` to every client. Must be
    /// called inside a tokio runtime.
    pub async fn bind(
        addr: &str,
        bus: VirtualBus,
        config: ServerConfig,
    ) -> Result<Self, ServerError> {
        Self::bind_channels_inner(addr, Channels::Any(bus), config).await
    }

    /// Listen on `addr` and serve one bus per name: a client's `< open NAME >` reaches the
    /// bus of that name only, and an unknown name is refused with the names there are.
    pub async fn bind_channels(
        addr: &str,
        channels: Vec<(String, VirtualBus)>,
        config: ServerConfig,
    ) -> Result<Self, ServerError> {
        Self::bind_channels_inner(addr, Channels::Named(channels), config).await
    }

    async fn bind_channels_inner(
        addr: &str,
        channels: Channels,
        config: ServerConfig,
    ) -> Result<Self, ServerError> {
        let listener = TcpListener::bind(addr)
            .await
            .map_err(|source| ServerError::Bind {
                addr: addr.to_owned(),
                source,
            })?;
        let local_addr = listener.local_addr().map_err(|source| ServerError::Bind {
            addr: addr.to_owned(),
            source,
        })?;
        let shared = Arc::new(Shared {
            channels,
            config,
            counters: Counters::default(),
            next_connection: AtomicU64::new(0),
            graces: Mutex::new(Vec::new()),
        });
        let (stop, stopped) = watch::channel(false);
        let task = tokio::spawn(accept_loop(listener, Arc::clone(&shared), stopped));
        tracing::info!(%local_addr, "socketcand server listening");
        Ok(Self {
            local_addr,
            shared: Arc::new(SharedHandle(shared)),
            stop,
            task: Some(task),
        })
    }

    /// A real-time virtual bus served on `addr`, as a separate emulator process offers its
    /// bus: frames are stamped with Unix time, as a SocketCAN socket stamps them. Returns the
    /// bus (for the emulator's node and any taps) and the server.
    pub async fn bind_realtime_bus(addr: &str) -> Result<(VirtualBus, Self), ServerError> {
        let epoch = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        let bus = VirtualBus::new(crate::virtual_bus::VirtualBusConfig {
            epoch,
            ..crate::virtual_bus::VirtualBusConfig::default()
        });
        let server = Self::bind(addr, bus.clone(), ServerConfig::default()).await?;
        Ok((bus, server))
    }

    /// Real-time virtual buses, one per name in `names`, served on `addr` as
    /// [`SocketcandServer::bind_channels`] does (timestamps in Unix time, as
    /// [`SocketcandServer::bind_realtime_bus`]). Returns the buses in `names` order.
    pub async fn bind_realtime_channels(
        addr: &str,
        names: &[String],
    ) -> Result<(Vec<VirtualBus>, Self), ServerError> {
        let epoch = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        let buses: Vec<VirtualBus> = names
            .iter()
            .map(|_| {
                VirtualBus::new(crate::virtual_bus::VirtualBusConfig {
                    epoch,
                    ..crate::virtual_bus::VirtualBusConfig::default()
                })
            })
            .collect();
        let channels = names.iter().cloned().zip(buses.iter().cloned()).collect();
        let server = Self::bind_channels(addr, channels, ServerConfig::default()).await?;
        Ok((buses, server))
    }

    /// The address the server listens on (the actual port when bound to port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Counters so far.
    pub fn stats(&self) -> ServerStats {
        self.shared.0.counters.snapshot()
    }

    /// Stop accepting, close every connection and wait until they are closed.
    pub async fn shutdown(mut self) {
        self.stop.send_replace(true);
        if let Some(task) = self.task.take() {
            let _ = task.await;
        }
    }
}

impl Drop for SocketcandServer {
    fn drop(&mut self) {
        self.stop.send_replace(true);
    }
}

async fn accept_loop(listener: TcpListener, shared: Arc<Shared>, mut stop: watch::Receiver<bool>) {
    // Dropping the set (on stop) aborts every connection task, which closes its socket and
    // detaches its node.
    let mut connections = JoinSet::new();
    loop {
        tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, peer)) => {
                    // Reap the connections that ended, so the count is of live ones.
                    while connections.try_join_next().is_some() {}
                    if connections.len() >= shared.config.max_clients.max(1) {
                        drop(stream);
                        let refused = shared.counters.refused.fetch_add(1, Ordering::Relaxed) + 1;
                        // A storm must not flood the log: the 1st, 2nd, 4th, 8th, … refusal.
                        if refused.is_power_of_two() {
                            tracing::warn!(%peer, refused, cap = shared.config.max_clients, "socketcand server full; connection closed");
                        }
                        continue;
                    }
                    connections.spawn(serve(stream, peer, Arc::clone(&shared)));
                }
                Err(error) => {
                    // E.g. out of file descriptors: keep serving the clients we have.
                    tracing::warn!(%error, "socketcand accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                }
            },
            Some(_) = connections.join_next(), if !connections.is_empty() => {}
            changed = stop.changed() => {
                if changed.is_err() || *stop.borrow() {
                    break;
                }
            }
        }
    }
    connections.shutdown().await;
    tracing::info!("socketcand server stopped");
}

/// Why a connection ended.
#[derive(Debug)]
enum End {
    ClientClosed,
    ReadFailed(std::io::Error),
    Http(super::http_guard::HttpRefused),
    WriteFailed(std::io::Error),
    BusClosed,
}

impl std::fmt::Display for End {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::ClientClosed => write!(f, "client closed the connection"),
            Self::ReadFailed(e) => write!(f, "reading from the client failed: {e}"),
            Self::Http(e) => write!(f, "closed: {e}"),
            Self::WriteFailed(e) => write!(f, "writing to the client failed: {e}"),
            Self::BusClosed => write!(f, "the bus was closed"),
        }
    }
}

/// Tracks one client gauge for the life of a connection.
struct ClientGauge<'a>(&'a Counters);

impl Drop for ClientGauge<'_> {
    fn drop(&mut self) {
        self.0.clients.fetch_sub(1, Ordering::Relaxed);
    }
}

/// How long a connection whose client is gone keeps reading what the client sent before it
/// left (the kernel has it all by then: this bounds only a peer that half-closed and goes on
/// sending).
const DRAIN_READ_LIMIT: Duration = Duration::from_secs(2);

/// What one connection dropped, each kind logged as one summary a second (D10).
#[derive(Debug, Default)]
struct DropLogs {
    /// Replies (`< ok >`, `< error … >`) dropped from a full queue.
    replies: Mutex<DropSummary>,
    /// Bus frames dropped from a full queue.
    frames: Mutex<DropSummary>,
}

impl DropLogs {
    fn reply_dropped(&self, peer: SocketAddr, reply: &Reply) {
        let mut summary = lock(&self.replies);
        if let Some(dropped) = summary.record(Instant::now()) {
            tracing::warn!(
                %peer,
                dropped,
                total = summary.total(),
                last = ?reply,
                "client queue full; replies dropped (one summary a second at most)"
            );
        }
    }

    fn frame_dropped(&self, peer: SocketAddr) {
        let mut summary = lock(&self.frames);
        if let Some(dropped) = summary.record(Instant::now()) {
            tracing::warn!(
                %peer,
                dropped,
                total = summary.total(),
                "client is not reading; frames for it dropped (one summary a second at most)"
            );
        }
    }

    /// Log what was dropped since the last summaries (the connection is ending).
    fn finish(&self, peer: SocketAddr) {
        let mut replies = lock(&self.replies);
        if let Some(dropped) = replies.take() {
            let total = replies.total();
            tracing::warn!(%peer, dropped, total, "client queue full; replies dropped");
        }
        let mut frames = lock(&self.frames);
        if let Some(dropped) = frames.take() {
            let total = frames.total();
            tracing::warn!(%peer, dropped, total, "client is not reading; frames for it dropped");
        }
    }
}

/// A poisoned lock only means another part of this connection panicked; the count is still
/// good for a log line.
fn lock(summary: &Mutex<DropSummary>) -> std::sync::MutexGuard<'_, DropSummary> {
    summary
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

async fn serve(stream: TcpStream, peer: SocketAddr, shared: Arc<Shared>) {
    let counters = &shared.counters;
    counters.connections.fetch_add(1, Ordering::Relaxed);
    counters.clients.fetch_add(1, Ordering::Relaxed);
    let _gauge = ClientGauge(counters);
    tracing::info!(%peer, "socketcand client connected");
    // Frames are small and latency matters more than packet count.
    if let Err(error) = stream.set_nodelay(true) {
        tracing::debug!(%peer, %error, "cannot set TCP_NODELAY");
    }
    let sock = socket2::SockRef::from(&stream);
    if let Err(error) = sock.set_send_buffer_size(shared.config.send_buffer) {
        tracing::debug!(%peer, %error, "cannot set SO_SNDBUF");
    }
    let (read, write) = stream.into_split();
    let (out, out_rx) = mpsc::channel(shared.config.client_queue.max(1));
    let (node_tx, node_rx) = watch::channel(None);
    let (raw_tx, raw_rx) = watch::channel(None);
    let raw_tx = Arc::new(raw_tx);
    let id = shared.next_connection.fetch_add(1, Ordering::Relaxed);
    lock_graces(&shared).push(GraceEntry {
        id,
        ip: peer.ip(),
        raw: Arc::downgrade(&raw_tx),
    });
    let drops = DropLogs::default();
    let mut session = Session {
        id,
        peer,
        shared: &shared,
        out: out.clone(),
        node: node_tx,
        raw: raw_tx,
        drops: &drops,
    };
    session.reply(Reply::Hi);
    let forwarder = Forwarder {
        peer,
        shared: &shared,
        out,
        drops: &drops,
    };
    let end = {
        let reader = session.read_loop(read);
        tokio::pin!(reader);
        let (end, read_all) = tokio::select! {
            end = &mut reader => (end, true),
            end = write_loop(write, out_rx) => (end, false),
            end = forwarder.run(node_rx, raw_rx) => (end, false),
        };
        // The client may be gone with elements still unread: a send-and-exit tool closes
        // right after its last `send`, and one that never reads is reset by its kernel (the
        // server's writes fail first). What it sent still goes on the bus, as a real
        // socketcand's kernel socket buffer would deliver it.
        if !read_all && matches!(end, End::WriteFailed(_) | End::ClientClosed) {
            match tokio::time::timeout(DRAIN_READ_LIMIT, &mut reader).await {
                Ok(read_end) => tracing::debug!(%peer, reason = %read_end, "client input drained"),
                Err(_) => tracing::debug!(%peer, "client input not drained in time"),
            }
        }
        end
    };
    let node = session.node.borrow().clone();
    if let Some(node) = node {
        // A connection closed for speaking HTTP has nothing of its own to deliver.
        if !matches!(end, End::Http(_)) {
            flush_transmit_queue(&node, shared.config.send_wait, peer).await;
        }
        node.close().await;
    }
    lock_graces(&shared).retain(|entry| entry.id != id);
    drops.finish(peer);
    tracing::info!(%peer, reason = %end, "socketcand client disconnected");
}

/// The list only holds weak handles: a panic elsewhere leaves it usable.
fn lock_graces(shared: &Shared) -> std::sync::MutexGuard<'_, Vec<GraceEntry>> {
    shared
        .graces
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Wait (at most `limit`) until every frame the client sent has left its node's transmit
/// queue: closing the node discards what is still queued.
async fn flush_transmit_queue(node: &VirtualNode, limit: Duration, peer: SocketAddr) {
    let deadline = Instant::now() + limit;
    loop {
        let pending = node.pending_tx();
        if pending == 0 {
            return;
        }
        if Instant::now() >= deadline {
            tracing::warn!(%peer, pending, "client's last frames not sent before it closed (bus busy or delayed)");
            return;
        }
        // A frame takes about 130 µs on a 1 Mbit/s wire; the queue holds 64 by default.
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
}

/// The command side of a connection.
struct Session<'a> {
    /// This connection's number in accept order.
    id: u64,
    peer: SocketAddr,
    shared: &'a Shared,
    out: mpsc::Sender<String>,
    /// The client's node, once it opened the bus.
    node: watch::Sender<Option<Arc<VirtualNode>>>,
    /// In raw mode: when frames start to be written to the client.
    raw: Arc<watch::Sender<Option<Instant>>>,
    drops: &'a DropLogs,
}

impl Session<'_> {
    async fn read_loop(&mut self, mut read: OwnedReadHalf) -> End {
        let mut framer = Framer::default();
        let mut guard = HttpGuard::new();
        let mut buf = vec![0u8; 8192];
        loop {
            let n = match read.read(&mut buf).await {
                Ok(0) => return End::ClientClosed,
                Ok(n) => n,
                Err(error) => return End::ReadFailed(error),
            };
            // The only way from the socket to the framer: nothing of an HTTP request runs.
            match guard.admit(&buf[..n]) {
                Ok(clean) => framer.push(clean),
                Err(refused) => {
                    self.shared
                        .counters
                        .http_refused
                        .fetch_add(1, Ordering::Relaxed);
                    tracing::warn!(peer = %self.peer, %refused, "socketcand server closes a connection that speaks HTTP (a web page's request?)");
                    return End::Http(refused);
                }
            }
            while let Some(element) = framer.next_element() {
                let text = match element {
                    Element::Complete(text) => text,
                    Element::Garbage(junk) => {
                        let shown: String = junk.chars().take(40).collect();
                        self.reply(Reply::Error(format!(
                            "ignored text outside an element: {shown:?}"
                        )));
                        continue;
                    }
                };
                if let Err(end) = self.handle(&text).await {
                    return end;
                }
            }
        }
    }

    /// Queue a reply; a full queue drops it (the client is not reading anyway).
    fn reply(&self, reply: Reply) {
        let counters = &self.shared.counters;
        if matches!(reply, Reply::Error(_)) {
            counters.errors.fetch_add(1, Ordering::Relaxed);
        }
        match self.out.try_send(protocol::format_reply(&reply)) {
            Ok(()) => {}
            Err(mpsc::error::TrySendError::Full(_)) => self.drops.reply_dropped(self.peer, &reply),
            // The writer is gone with the client; its last elements are being drained.
            Err(mpsc::error::TrySendError::Closed(_)) => {}
        }
    }

    async fn handle(&mut self, text: &str) -> Result<(), End> {
        let command = match protocol::parse_command(text) {
            Ok(command) => command,
            Err(error) => {
                tracing::debug!(peer = %self.peer, %error, text, "malformed socketcand element");
                self.reply(Reply::Error(error.to_string()));
                return Ok(());
            }
        };
        if command != Command::RawMode {
            end_grace(&self.raw);
        }
        let node = self.node.borrow().clone();
        match (command, node) {
            (Command::Open(name), None) => {
                let bus = match self.shared.channels.open(&name) {
                    Ok(bus) => bus,
                    Err(refusal) => {
                        tracing::debug!(peer = %self.peer, bus = name, "unknown bus refused");
                        self.reply(Reply::Error(refusal));
                        return Ok(());
                    }
                };
                let options = NodeOptions {
                    receive_own: false,
                    tx_queue_len: Some(self.shared.config.node_tx_queue),
                };
                let node = bus.attach_with(&format!("socketcand {}", self.peer), options);
                tracing::debug!(peer = %self.peer, bus = name, "bus opened");
                self.node.send_replace(Some(Arc::new(node)));
                self.reply(Reply::Ok);
            }
            (Command::Open(_), Some(_)) => self.reply(Reply::Error("a bus is already open".into())),
            (Command::Echo, _) => self.reply(Reply::Echo),
            (_, None) => self.reply(Reply::Error("no bus open: send `open NAME` first".into())),
            (Command::RawMode, Some(_)) => {
                let start = Instant::now() + self.shared.config.rawmode_grace;
                self.raw.send_replace(Some(start));
                self.end_earlier_graces();
                self.reply(Reply::Ok);
            }
            (Command::BcmMode, Some(_)) => {
                self.raw.send_replace(None);
                self.reply(Reply::Ok);
            }
            (Command::Send(frame), Some(node)) => self.send(&node, frame).await?,
        }
        Ok(())
    }

    /// End the grace period of the connections the same client opened before this one.
    ///
    /// python-can opens a connection in its constructor, which returns only after it has
    /// read the `< ok >` to `< rawmode >`; so when a later connection from the same address
    /// reaches `< rawmode >`, the earlier ones have read theirs. piper_sdk on Linux reads on
    /// one connection and sends on a second opened right after it, and asks for the firmware
    /// version at once on the second: without this the reading connection would get the
    /// answer only when its grace ends, later than the 30 ms the vendor's example waits.
    fn end_earlier_graces(&self) {
        let ip = self.peer.ip();
        let graces = lock_graces(self.shared);
        for entry in graces.iter().filter(|e| e.ip == ip && e.id < self.id) {
            if let Some(raw) = entry.raw.upgrade() {
                end_grace(&raw);
            }
        }
    }

    /// Put a client's frame on the bus, waiting (and so not reading that client) while its
    /// transmit queue is full.
    async fn send(&self, node: &VirtualNode, frame: CanFrame) -> Result<(), End> {
        let deadline = Instant::now() + self.shared.config.send_wait;
        loop {
            match node.send(frame).await {
                Ok(()) => {
                    let counters = &self.shared.counters;
                    counters.frames_from_clients.fetch_add(1, Ordering::Relaxed);
                    return Ok(());
                }
                Err(BusError::TxQueueFull { .. }) if Instant::now() < deadline => {
                    tokio::time::sleep(Duration::from_micros(200)).await;
                }
                Err(BusError::Closed) => return Err(End::BusClosed),
                Err(error) => {
                    self.reply(Reply::Error(format!("frame {frame} not sent: {error}")));
                    return Ok(());
                }
            }
        }
    }
}

/// The bus side of a connection.
struct Forwarder<'a> {
    peer: SocketAddr,
    shared: &'a Shared,
    out: mpsc::Sender<String>,
    drops: &'a DropLogs,
}

/// What the forwarder does with a frame from the bus, by the connection's mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Forwarding {
    /// Not in raw mode: nothing is forwarded (socketcand has no raw socket yet).
    Off,
    /// In raw mode's grace period: held until it ends.
    Held { until: Instant },
    /// In raw mode: written to the client.
    On,
}

impl Forwarding {
    fn of(raw: &watch::Receiver<Option<Instant>>, now: Instant) -> Self {
        match *raw.borrow() {
            None => Self::Off,
            Some(start) if start > now => Self::Held { until: start },
            Some(_) => Self::On,
        }
    }
}

impl Forwarder<'_> {
    async fn run(
        self,
        mut node: watch::Receiver<Option<Arc<VirtualNode>>>,
        raw: watch::Receiver<Option<Instant>>,
    ) -> End {
        // An error means the session is gone, and with it the connection.
        let opened = node
            .wait_for(Option::is_some)
            .await
            .ok()
            .and_then(|n| n.clone());
        let Some(node) = opened else {
            return std::future::pending().await;
        };
        match self.forward(&node, raw).await {
            Err(end) => end,
            Ok(never) => match never {},
        }
    }

    /// Forward frames from the client's node until the connection ends.
    async fn forward(
        &self,
        node: &VirtualNode,
        mut raw: watch::Receiver<Option<Instant>>,
    ) -> Result<std::convert::Infallible, End> {
        // Frames of the grace period, formatted, oldest first.
        let mut held: VecDeque<String> = VecDeque::new();
        let mut raw_open = true;
        loop {
            let mode = Forwarding::of(&raw, Instant::now());
            let grace_end = match mode {
                Forwarding::Held { until } if !held.is_empty() => Some(until),
                _ => None,
            };
            tokio::select! {
                received = node.recv() => {
                    let Ok(received) = received else {
                        return Err(End::BusClosed);
                    };
                    if received.frame.is_fd() {
                        // No form a client understands (see the protocol module).
                        if Forwarding::of(&raw, Instant::now()) != Forwarding::Off {
                            self.fd_not_forwarded();
                        }
                        continue;
                    }
                    // The node drains the bus in every mode; only raw mode forwards.
                    match Forwarding::of(&raw, Instant::now()) {
                        Forwarding::Off => {}
                        Forwarding::Held { .. } => {
                            let text = protocol::format_frame(&received.frame, received.timestamp);
                            if held.len() < self.shared.config.client_queue.max(1) {
                                held.push_back(text);
                            } else {
                                self.dropped();
                            }
                        }
                        Forwarding::On => {
                            self.release(&mut held)?;
                            let text = protocol::format_frame(&received.frame, received.timestamp);
                            self.deliver(text)?;
                        }
                    }
                }
                () = tokio::time::sleep_until(grace_end.unwrap_or_else(Instant::now)), if grace_end.is_some() => {
                    self.release(&mut held)?;
                }
                changed = raw.changed(), if raw_open => {
                    if changed.is_err() {
                        raw_open = false;
                        continue;
                    }
                    match Forwarding::of(&raw, Instant::now()) {
                        // `< bcmmode >`: what the raw socket had not delivered goes with it.
                        Forwarding::Off => held.clear(),
                        Forwarding::Held { .. } => {}
                        // Ended early: by the client's next command or next connection.
                        Forwarding::On => self.release(&mut held)?,
                    }
                }
            }
        }
    }

    /// Queue the frames held in the grace period, oldest first.
    fn release(&self, held: &mut VecDeque<String>) -> Result<(), End> {
        while let Some(text) = held.pop_front() {
            self.deliver(text)?;
        }
        Ok(())
    }

    /// Queue one frame for the client; a full queue drops it, as a full SocketCAN receive
    /// queue would.
    fn deliver(&self, text: String) -> Result<(), End> {
        match self.out.try_send(text) {
            Ok(()) => {
                let counters = &self.shared.counters;
                counters.frames_to_clients.fetch_add(1, Ordering::Relaxed);
                Ok(())
            }
            Err(mpsc::error::TrySendError::Full(_)) => {
                self.dropped();
                Ok(())
            }
            Err(mpsc::error::TrySendError::Closed(_)) => Err(End::ClientClosed),
        }
    }

    /// Count a CAN FD frame left out; the server's first one is logged.
    fn fd_not_forwarded(&self) {
        let counters = &self.shared.counters;
        if counters
            .fd_frames_not_forwarded
            .fetch_add(1, Ordering::Relaxed)
            == 0
        {
            tracing::warn!(
                peer = %self.peer,
                "CAN FD frames on the bus are not forwarded to socketcand clients: the protocol \
                 python-can speaks has no CAN FD frame (counted in \
                 ServerStats::fd_frames_not_forwarded; logged once)"
            );
        }
    }

    fn dropped(&self) {
        let counters = &self.shared.counters;
        counters.frames_dropped.fetch_add(1, Ordering::Relaxed);
        self.drops.frame_dropped(self.peer);
    }
}

/// Largest write: python-can reads 1024 bytes at a time and warns about every element a read
/// cuts in two, so a write holds whole elements and fits one such read.
const MAX_WRITE: usize = 1024;

async fn write_loop(mut write: OwnedWriteHalf, mut queue: mpsc::Receiver<String>) -> End {
    let mut batch = Vec::with_capacity(MAX_WRITE + protocol::MAX_ELEMENT_LEN);
    let mut next = queue.recv().await;
    while let Some(first) = next.take() {
        batch.clear();
        batch.extend_from_slice(first.as_bytes());
        // What else is already queued goes out in the same write, up to MAX_WRITE.
        while let Ok(more) = queue.try_recv() {
            if batch.len() + more.len() > MAX_WRITE {
                next = Some(more);
                break;
            }
            batch.extend_from_slice(more.as_bytes());
        }
        if let Err(error) = write.write_all(&batch).await {
            return End::WriteFailed(error);
        }
        if next.is_none() {
            next = queue.recv().await;
        }
    }
    // Every sender is gone: the other parts have ended the connection already.
    End::ClientClosed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::virtual_bus::VirtualBusConfig;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    use tokio::time::timeout;

    const WAIT: Duration = Duration::from_secs(5);
    /// The e-stop a web page would send (Piper 0x150, first byte 1).
    const ESTOP: &str = "< open can0 >< send 150 8 01 00 00 00 00 00 00 00 >";

    async fn server(config: ServerConfig) -> (SocketcandServer, VirtualNode, String) {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let emulator = bus.attach("emulator");
        let server = SocketcandServer::bind("127.0.0.1:0", bus, config)
            .await
            .unwrap();
        let addr = server.local_addr().to_string();
        (server, emulator, addr)
    }

    /// Everything the server sends until it closes the connection (bounded by [`WAIT`]).
    /// A reset (the server closed with our request unread) counts as closed.
    async fn read_to_close(stream: &mut TcpStream) -> Option<String> {
        let mut seen = Vec::new();
        let _read = timeout(WAIT, stream.read_to_end(&mut seen)).await.ok()?;
        Some(String::from_utf8_lossy(&seen).into_owned())
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_browser_post_is_closed_and_puts_nothing_on_the_bus() {
        let (server, emulator, addr) = server(ServerConfig::default()).await;
        let request = format!(
            "POST / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nOrigin: https://attacker.example\r\n\
             Content-Type: text/plain;charset=UTF-8\r\nContent-Length: {len}\r\n\r\n{ESTOP}",
            port = server.local_addr().port(),
            len = ESTOP.len()
        );
        // Whole, and in small pieces (a request line split over TCP segments).
        for piece in [request.len(), 5] {
            let mut stream = TcpStream::connect(&addr).await.unwrap();
            for part in request.as_bytes().chunks(piece) {
                // The server may already have closed: later writes may fail.
                if stream.write_all(part).await.is_err() {
                    break;
                }
            }
            let seen = read_to_close(&mut stream).await;
            assert!(seen.is_some(), "the connection stayed open");
        }
        let frame = timeout(Duration::from_millis(300), emulator.recv()).await;
        assert!(frame.is_err(), "a frame reached the bus: {frame:?}");
        assert_eq!(server.stats().http_refused, 2);
        assert_eq!(server.stats().frames_from_clients, 0);

        // The same body from a socketcand client does reach the bus (the test can fail).
        let mut stream = TcpStream::connect(&addr).await.unwrap();
        stream.write_all(ESTOP.as_bytes()).await.unwrap();
        let frame = timeout(WAIT, emulator.recv()).await.unwrap().unwrap();
        assert_eq!(frame.frame.id().raw(), 0x150);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn connections_over_the_cap_are_closed_at_once() {
        let config = ServerConfig {
            max_clients: 3,
            ..ServerConfig::default()
        };
        let (server, _emulator, addr) = server(config).await;
        let mut kept = Vec::new();
        for _ in 0..3 {
            let mut stream = TcpStream::connect(&addr).await.unwrap();
            let mut hi = [0u8; 6];
            timeout(WAIT, stream.read_exact(&mut hi))
                .await
                .unwrap()
                .unwrap();
            assert_eq!(&hi, b"< hi >");
            kept.push(stream);
        }
        for _ in 0..5 {
            let mut extra = TcpStream::connect(&addr).await.unwrap();
            let seen = read_to_close(&mut extra).await;
            assert_eq!(seen.as_deref(), Some(""), "over the cap");
        }
        assert_eq!(server.stats().refused, 5);
        assert_eq!(server.stats().clients, 3);
        // A client that leaves makes room for the next.
        drop(kept.pop());
        let deadline = Instant::now() + WAIT;
        loop {
            let mut stream = TcpStream::connect(&addr).await.unwrap();
            let mut hi = [0u8; 6];
            if timeout(WAIT, stream.read_exact(&mut hi))
                .await
                .is_ok_and(|r| r.is_ok())
            {
                break;
            }
            assert!(Instant::now() < deadline, "no room after a client left");
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// The handshake exactly as python-can 4.6.1 does it: each answer read with one `recv`
    /// and compared whole, so an answer that arrives with anything after it fails.
    async fn python_can_handshake(addr: &str) -> TcpStream {
        async fn expect(stream: &mut TcpStream, answer: &str) {
            let mut buf = [0u8; 256];
            let n = timeout(WAIT, stream.read(&mut buf)).await.unwrap().unwrap();
            assert_eq!(
                String::from_utf8_lossy(&buf[..n]),
                answer,
                "one recv, compared whole"
            );
        }
        let mut stream = TcpStream::connect(addr).await.unwrap();
        expect(&mut stream, "< hi >").await;
        stream.write_all(b"< open can0 >").await.unwrap();
        expect(&mut stream, "< ok >").await;
        stream.write_all(b"< rawmode >").await.unwrap();
        expect(&mut stream, "< ok >").await;
        stream
    }

    /// Send on a node, waiting while its small transmit queue is full.
    async fn put(node: &VirtualNode, frame: CanFrame) {
        let deadline = Instant::now() + WAIT;
        loop {
            match node.send(frame).await {
                Ok(()) => return,
                Err(BusError::TxQueueFull { .. }) if Instant::now() < deadline => {
                    tokio::time::sleep(Duration::from_micros(200)).await;
                }
                Err(error) => panic!("send failed: {error}"),
            }
        }
    }

    /// The Piper's answer to a firmware query: its version string in 0x4AF frames.
    const FIRMWARE_BURST: [&[u8]; 2] = [b"S-V1.8-2", b"\0\0\0\0\0\0\0\0"];

    /// Issue 20 item 4, the connection sequence of piper_sdk 0.6.2 on Linux through
    /// python-can: it opens a connection it only reads (R), then one it only sends on (S),
    /// and sends the firmware query on S at once. R has sent nothing since its
    /// `< rawmode >`, so the answer comes while R would still be in its grace period (here
    /// 30 s, so that nothing but the end of the grace by S can deliver it in time). R must
    /// get the answer, and its `< ok >` must still arrive alone, with the arm's feedback
    /// running all the while.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn the_firmware_answer_reaches_the_connection_the_sdk_reads() {
        let config = ServerConfig {
            rawmode_grace: Duration::from_secs(30),
            ..ServerConfig::default()
        };
        let (_server, emulator, addr) = server(config).await;
        let arm = emulator.clone();
        // The emulator: each firmware query answered at once, feedback every millisecond.
        tokio::spawn(async move {
            while let Ok(received) = emulator.recv().await {
                if received.frame.raw_id() == 0x4AF {
                    for chunk in FIRMWARE_BURST {
                        put(&emulator, CanFrame::standard(0x4AF, chunk).unwrap()).await;
                    }
                }
            }
        });
        let feedback = tokio::spawn(async move {
            loop {
                put(&arm, CanFrame::standard(0x2A1, &[0x11; 8]).unwrap()).await;
                tokio::time::sleep(Duration::from_millis(1)).await;
            }
        });
        let mut reader = python_can_handshake(&addr).await;
        let mut sender = python_can_handshake(&addr).await;
        sender
            .write_all(b"< send 4AF 8 1 0 0 0 0 0 0 0 >")
            .await
            .unwrap();
        let mut seen = String::new();
        let mut buf = [0u8; 1024];
        let wanted = ["532D56312E382D32", "0000000000000000"];
        timeout(WAIT, async {
            while !wanted.iter().all(|w| seen.contains(w)) {
                let n = reader.read(&mut buf).await.unwrap();
                assert!(n > 0, "closed; got {seen:?}");
                seen.push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        })
        .await
        .unwrap_or_else(|_| {
            panic!(
                "the firmware answer never reached the reader; got {} bytes",
                seen.len()
            )
        });
        feedback.abort();
        // In order, and as 0x4AF frames.
        let first = seen.find("< frame 4AF ").unwrap();
        let version = seen.find("532D56312E382D32").unwrap();
        let rest = seen.find("0000000000000000").unwrap();
        assert!(first < version && version < rest, "{seen}");
    }

    /// Frames on the bus before `< rawmode >` are not delivered (socketcand opens its raw
    /// socket there), but none after it is lost.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn frames_before_rawmode_are_not_delivered_and_none_after_it_is_lost() {
        let (_server, emulator, addr) = server(ServerConfig::default()).await;
        let mut stream = TcpStream::connect(&addr).await.unwrap();
        stream.write_all(b"< open can0 >").await.unwrap();
        let mut seen = String::new();
        let mut buf = [0u8; 1024];
        while seen.matches("< ok >").count() < 1 {
            let n = timeout(WAIT, stream.read(&mut buf)).await.unwrap().unwrap();
            seen.push_str(&String::from_utf8_lossy(&buf[..n]));
        }
        put(&emulator, CanFrame::standard(0x100, &[1]).unwrap()).await;
        tokio::time::sleep(Duration::from_millis(50)).await;
        stream.write_all(b"< rawmode >").await.unwrap();
        // Right after `< rawmode >` (in its grace), and well after it.
        tokio::time::sleep(Duration::from_millis(10)).await;
        for i in 0..20u8 {
            put(&emulator, CanFrame::standard(0x200, &[i]).unwrap()).await;
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        timeout(WAIT, async {
            while !seen.contains("< frame 200 ") || !seen.contains(" 13 >") {
                let n = stream.read(&mut buf).await.unwrap();
                assert!(n > 0, "closed; got {seen:?}");
                seen.push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        })
        .await
        .unwrap_or_else(|_| panic!("frames after rawmode missing; got {seen:?}"));
        assert!(
            !seen.contains("< frame 100 "),
            "a frame from before rawmode: {seen}"
        );
        let payloads: Vec<String> = seen
            .split("< frame 200 ")
            .skip(1)
            .map(|f| f.split(' ').nth(1).unwrap_or_default().to_owned())
            .collect();
        let expected: Vec<String> = (0..20u8).map(|i| format!("{i:02X}")).collect();
        assert_eq!(payloads, expected, "{seen}");
    }

    /// The frames of a `send` sequence, numbered in their first two bytes.
    fn numbered_sends(count: u16) -> String {
        (0..count)
            .map(|i| format!("< send 123 2 {:X} {:X} >", i & 0xFF, i >> 8))
            .collect()
    }

    /// Receive `count` numbered 0x123 frames on `node`, in order, within [`WAIT`].
    async fn expect_numbered(node: &VirtualNode, count: u16) {
        for i in 0..count {
            let frame = timeout(WAIT, async {
                loop {
                    let frame = node.recv().await.unwrap().frame;
                    if frame.raw_id() == 0x123 {
                        return frame;
                    }
                }
            })
            .await
            .unwrap_or_else(|_| panic!("frame {i} of {count} never reached the bus"));
            assert_eq!(
                frame.data(),
                [(i & 0xFF) as u8, (i >> 8) as u8],
                "frame {i}"
            );
        }
    }

    /// D15: a send-and-exit tool writes its frames and closes at once. Every frame goes on
    /// the bus, also more than the client's transmit queue holds.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn frames_sent_just_before_close_all_reach_the_bus() {
        let (server, emulator, addr) = server(ServerConfig::default()).await;
        for count in [5, 300] {
            let mut stream = TcpStream::connect(&addr).await.unwrap();
            let script = format!("< open can0 >{}", numbered_sends(count));
            stream.write_all(script.as_bytes()).await.unwrap();
            drop(stream);
            expect_numbered(&emulator, count).await;
        }
        assert_eq!(server.stats().frames_from_clients, 305);
    }

    /// D15 when the client is in raw mode and reads nothing: its close is a reset (unread
    /// data in its socket), and the server's writes fail before its reads end. What it sent
    /// still reaches the bus.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn frames_sent_before_a_reset_all_reach_the_bus() {
        let (_server, emulator, addr) = server(ServerConfig::default()).await;
        let mut stream = python_can_handshake(&addr).await;
        // Traffic the client never reads, past the grace period.
        for i in 0..200u8 {
            put(&emulator, CanFrame::standard(0x2A1, &[i]).unwrap()).await;
            if i % 8 == 0 {
                tokio::time::sleep(Duration::from_millis(2)).await;
            }
        }
        tokio::time::sleep(Duration::from_millis(150)).await;
        let count = 100;
        stream
            .write_all(numbered_sends(count).as_bytes())
            .await
            .unwrap();
        // Unread data in its receive buffer: the kernel resets instead of closing cleanly.
        drop(stream);
        expect_numbered(&emulator, count).await;
    }

    /// A CAN FD frame has no form python-can reads: clients in raw mode do not get it (the
    /// server counts it), they still get the classic frames around it, and armhil's client
    /// refuses to send one.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn fd_frames_are_counted_not_forwarded() {
        let bus = VirtualBus::new(VirtualBusConfig {
            data_bitrate_bps: Some(5_000_000),
            ..VirtualBusConfig::default()
        });
        let emulator = bus.attach("emulator");
        let server = SocketcandServer::bind("127.0.0.1:0", bus, ServerConfig::default())
            .await
            .unwrap();
        let addr = server.local_addr().to_string();
        let client = super::super::SocketcandBus::connect(&addr, "can0")
            .await
            .unwrap();
        let fd = CanFrame::fd(
            crate::CanId::Standard(0x123),
            &[0xAB; 64],
            crate::FdFlags {
                brs: true,
                esi: false,
            },
        )
        .unwrap();
        put(&emulator, CanFrame::standard(0x100, &[1]).unwrap()).await;
        put(&emulator, fd).await;
        put(&emulator, CanFrame::standard(0x101, &[2]).unwrap()).await;
        let first = timeout(WAIT, client.recv()).await.unwrap().unwrap();
        let second = timeout(WAIT, client.recv()).await.unwrap().unwrap();
        assert_eq!(
            [first.frame.raw_id(), second.frame.raw_id()],
            [0x100, 0x101]
        );
        assert!(!first.frame.is_fd() && !second.frame.is_fd());
        assert_eq!(server.stats().fd_frames_not_forwarded, 1);
        assert_eq!(server.stats().frames_to_clients, 2);
        let Err(error) = client.send(fd).await else {
            panic!("a CAN FD frame was accepted for socketcand");
        };
        let text = error.to_string();
        assert!(
            text.contains("CAN FD frame 123 (64 bytes) not sent: the socketcand protocol carries classic CAN frames only"),
            "{text}"
        );
    }
}
