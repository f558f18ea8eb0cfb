//! The emulator's transport: a TCP listener (real time) or in-memory duplex streams (virtual
//! time) feeding one [`Controller`], a 1 kHz core task, and the UDP realtime push.
//!
//! Every connection runs the same generic code over `AsyncRead + AsyncWrite`: a reader that
//! splits requests ([`Splitter`](crate::realman::framing::Splitter)), answers them under the
//! controller lock and queues the reply, and a writer that writes each queued message (reply
//! or event) as its own write (compact JSON and CRLF). Replies and events share the client's
//! queue, so an acknowledgement always precedes the arrival event of its move and the two
//! never share a write.
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
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tokio::sync::{mpsc, watch};
use tokio::time::Instant;

use super::firmware::{ClientId, Controller, ControllerConfig, ControllerError};
use super::push::{PushFaults, PushStats};

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

mod connection;
mod core_task;
mod fault_injection;
mod handle;
mod monitor;
mod tcp;
#[cfg(test)]
mod tests;

pub use handle::{RealmanEmulator, RealmanHandle};
pub use monitor::RealmanMonitor;
