//! The UDP realtime state stream, decoded and published.
//!
//! Several arms of one process may receive their controllers' pushes on one local UDP port (a
//! bimanual setup aims both controllers at the same `udp_port`): [`StateFeed::shared`] binds
//! each local address once and routes every datagram by its source address to the feeds of
//! that controller ([`route`]).

use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock, Weak};

use tokio::net::UdpSocket;
use tokio::sync::{broadcast, mpsc, watch};
use tokio::task::JoinHandle;

use crate::realman::codec::push::{decode_push, ArmState, JointSpeedUnit};

/// Decoded realtime state: the latest sample on a watch, every sample on a broadcast.
pub struct StateFeed {
    latest: watch::Receiver<Option<Arc<ArmState>>>,
    samples: broadcast::Sender<Arc<ArmState>>,
    decode_errors: Arc<AtomicU64>,
    local_addr: Option<std::net::SocketAddr>,
    /// The receiving task of a feed that owns its input.
    task: Option<JoinHandle<()>>,
    /// This feed's place on a shared socket (dropping it unregisters the feed).
    route: Option<RouteGuard>,
}

impl Drop for StateFeed {
    fn drop(&mut self) {
        if let Some(t) = &self.task {
            t.abort();
        }
    }
}

/// The feeds a datagram from `from` goes to, given each feed's controller address.
///
/// - One controller on the socket (one arm, or several arms of one controller): every feed,
///   whatever the source — a NAT or a second interface may change the source address, and a
///   lone controller needs no routing.
/// - Several controllers: the feeds whose controller address is the source exactly (IP and
///   port); failing that, the feeds of the one controller with the source's IP. A source that
///   matches no controller, or only the IP of several, is routed nowhere (counted).
pub fn route(feeds: &[(u64, SocketAddr)], from: SocketAddr) -> Vec<u64> {
    let mut controllers: Vec<SocketAddr> = feeds.iter().map(|(_, c)| *c).collect();
    controllers.sort();
    controllers.dedup();
    let of = |c: SocketAddr| -> Vec<u64> {
        feeds
            .iter()
            .filter(|(_, fc)| *fc == c)
            .map(|(id, _)| *id)
            .collect()
    };
    match controllers.as_slice() {
        [] => Vec::new(),
        [only] => of(*only),
        many => {
            if many.contains(&from) {
                return of(from);
            }
            let same_ip: Vec<SocketAddr> = many
                .iter()
                .copied()
                .filter(|c| c.ip() == from.ip())
                .collect();
            match same_ip.as_slice() {
                [one] => of(*one),
                _ => Vec::new(),
            }
        }
    }
}

/// One bound UDP socket and the feeds it serves.
struct SharedSocket {
    local: SocketAddr,
    feeds: Mutex<Vec<(u64, SocketAddr, Publisher)>>,
    next_id: AtomicU64,
    unrouted: AtomicU64,
    task: Mutex<Option<JoinHandle<()>>>,
}

impl Drop for SharedSocket {
    fn drop(&mut self) {
        if let Some(t) = self.task.get_mut().ok().and_then(Option::take) {
            t.abort();
        }
    }
}

impl SharedSocket {
    fn feeds(&self) -> std::sync::MutexGuard<'_, Vec<(u64, SocketAddr, Publisher)>> {
        // Poisoning only means a panic elsewhere; the list itself stays consistent.
        self.feeds.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn dispatch(&self, datagram: &[u8], from: SocketAddr) {
        let feeds = self.feeds();
        let keys: Vec<(u64, SocketAddr)> = feeds.iter().map(|(id, c, _)| (*id, *c)).collect();
        let targets = route(&keys, from);
        if targets.is_empty() {
            self.unrouted.fetch_add(1, Ordering::Relaxed);
            tracing::debug!(%from, "state datagram from no known controller dropped");
            return;
        }
        for (id, _, p) in feeds.iter() {
            if targets.contains(id) {
                p.publish(datagram);
            }
        }
    }
}

/// A feed's registration on a shared socket.
struct RouteGuard {
    socket: Arc<SharedSocket>,
    id: u64,
}

impl Drop for RouteGuard {
    fn drop(&mut self) {
        self.socket.feeds().retain(|(id, _, _)| *id != self.id);
    }
}

/// The sockets shared in this process, by the address they were asked to bind.
type Registry = Mutex<Vec<(SocketAddr, Weak<SharedSocket>)>>;

fn registry() -> &'static Registry {
    static SOCKETS: OnceLock<Registry> = OnceLock::new();
    SOCKETS.get_or_init(|| Mutex::new(Vec::new()))
}

/// The live shared socket for `addr`, or a new one bound to it.
async fn shared_socket(addr: SocketAddr) -> std::io::Result<Arc<SharedSocket>> {
    let find = || {
        let mut reg = registry().lock().unwrap_or_else(|p| p.into_inner());
        reg.retain(|(_, w)| w.strong_count() > 0);
        reg.iter()
            .find(|(a, _)| *a == addr)
            .and_then(|(_, w)| w.upgrade())
    };
    if let Some(s) = find() {
        return Ok(s);
    }
    let socket = UdpSocket::bind(addr).await?;
    let shared = Arc::new(SharedSocket {
        local: socket.local_addr()?,
        feeds: Mutex::new(Vec::new()),
        next_id: AtomicU64::new(1),
        unrouted: AtomicU64::new(0),
        task: Mutex::new(None),
    });
    let weak = Arc::downgrade(&shared);
    let task = tokio::spawn(async move {
        let mut buf = vec![0u8; 65_536];
        loop {
            match socket.recv_from(&mut buf).await {
                Ok((n, from)) => match weak.upgrade() {
                    Some(s) => s.dispatch(&buf[..n], from),
                    None => break,
                },
                Err(e) => tracing::warn!(error = %e, "state socket receive failed"),
            }
        }
    });
    *shared.task.lock().unwrap_or_else(|p| p.into_inner()) = Some(task);
    let mut reg = registry().lock().unwrap_or_else(|p| p.into_inner());
    // Another arm may have bound the same address meanwhile (the bind above then failed for
    // one of the two); the first registered wins.
    if let Some(existing) = reg
        .iter()
        .find(|(a, _)| *a == addr)
        .and_then(|(_, w)| w.upgrade())
    {
        return Ok(existing);
    }
    reg.push((addr, Arc::downgrade(&shared)));
    Ok(shared)
}

struct Publisher {
    latest: watch::Sender<Option<Arc<ArmState>>>,
    samples: broadcast::Sender<Arc<ArmState>>,
    decode_errors: Arc<AtomicU64>,
    unit: JointSpeedUnit,
}

impl Publisher {
    fn publish(&self, datagram: &[u8]) {
        match decode_push(datagram, self.unit) {
            Ok(state) => {
                let state = Arc::new(state);
                self.latest.send_replace(Some(state.clone()));
                let _ = self.samples.send(state);
            }
            Err(e) => {
                self.decode_errors.fetch_add(1, Ordering::Relaxed);
                tracing::debug!(error = %e, "undecodable state datagram");
            }
        }
    }
}

impl StateFeed {
    fn start(unit: JointSpeedUnit, run: impl FnOnce(Publisher) -> JoinHandle<()>) -> Self {
        let (latest_tx, latest) = watch::channel(None);
        let samples = broadcast::channel(256).0;
        let decode_errors = Arc::new(AtomicU64::new(0));
        let task = run(Publisher {
            latest: latest_tx,
            samples: samples.clone(),
            decode_errors: decode_errors.clone(),
            unit,
        });
        Self {
            latest,
            samples,
            decode_errors,
            local_addr: None,
            task: Some(task),
            route: None,
        }
    }

    /// Receives the datagrams that `controller` (its command address) pushes to `addr`,
    /// sharing the socket with every other feed of this process on the same `addr` (see
    /// `route` for which datagrams each feed gets). Port 0 binds a fresh port, never shared.
    /// The socket closes with its last feed.
    ///
    /// The receiving task runs on the runtime of the feed that bound the socket, so feeds
    /// sharing a socket must live on one runtime (as the Python binding's arms do).
    pub async fn shared(
        addr: SocketAddr,
        controller: SocketAddr,
        unit: JointSpeedUnit,
    ) -> std::io::Result<Self> {
        if addr.port() == 0 {
            return Self::bind(&addr.to_string(), unit).await;
        }
        let socket = shared_socket(addr).await?;
        let (latest_tx, latest) = watch::channel(None);
        let samples = broadcast::channel(256).0;
        let decode_errors = Arc::new(AtomicU64::new(0));
        let publisher = Publisher {
            latest: latest_tx,
            samples: samples.clone(),
            decode_errors: decode_errors.clone(),
            unit,
        };
        let id = socket.next_id.fetch_add(1, Ordering::Relaxed);
        socket.feeds().push((id, controller, publisher));
        Ok(Self {
            latest,
            samples,
            decode_errors,
            local_addr: Some(socket.local),
            task: None,
            route: Some(RouteGuard { socket, id }),
        })
    }

    /// Datagrams the shared socket under this feed could not route to any controller's feed
    /// (0 for a feed that owns its socket).
    pub fn unrouted(&self) -> u64 {
        self.route
            .as_ref()
            .map_or(0, |r| r.socket.unrouted.load(Ordering::Relaxed))
    }

    /// Receives datagrams on a bound UDP socket (real time).
    pub fn from_socket(socket: UdpSocket, unit: JointSpeedUnit) -> Self {
        let local_addr = socket.local_addr().ok();
        let mut feed = Self::start(unit, |p| {
            tokio::spawn(async move {
                let mut buf = vec![0u8; 65_536];
                loop {
                    match socket.recv_from(&mut buf).await {
                        Ok((n, _from)) => p.publish(&buf[..n]),
                        Err(e) => tracing::warn!(error = %e, "state socket receive failed"),
                    }
                }
            })
        });
        feed.local_addr = local_addr;
        feed
    }

    /// The local address of the UDP socket (None for a channel feed).
    pub fn local_addr(&self) -> Option<std::net::SocketAddr> {
        self.local_addr
    }

    /// Binds `addr` (e.g. `0.0.0.0:8089`) and receives on it.
    pub async fn bind(addr: &str, unit: JointSpeedUnit) -> std::io::Result<Self> {
        Ok(Self::from_socket(UdpSocket::bind(addr).await?, unit))
    }

    /// Receives datagrams from a channel (virtual time); ends when the sender is dropped.
    pub fn from_channel(mut datagrams: mpsc::Receiver<Vec<u8>>, unit: JointSpeedUnit) -> Self {
        Self::start(unit, |p| {
            tokio::spawn(async move {
                while let Some(d) = datagrams.recv().await {
                    p.publish(&d);
                }
            })
        })
    }

    /// The latest sample, if any arrived.
    pub fn latest(&self) -> Option<Arc<ArmState>> {
        self.latest.borrow().clone()
    }

    /// A watch on the latest sample.
    pub fn watch(&self) -> watch::Receiver<Option<Arc<ArmState>>> {
        self.latest.clone()
    }

    /// Every sample from now on.
    pub fn subscribe(&self) -> broadcast::Receiver<Arc<ArmState>> {
        self.samples.subscribe()
    }

    /// Datagrams that could not be decoded.
    pub fn decode_errors(&self) -> u64 {
        self.decode_errors.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a(s: &str) -> SocketAddr {
        s.parse().unwrap()
    }

    #[test]
    fn one_controller_takes_every_datagram_several_are_told_apart() {
        let one = [(1, a("192.168.1.18:8080")), (2, a("192.168.1.18:8080"))];
        // Two arms of one controller both get its push, from any source port or address.
        assert_eq!(route(&one, a("192.168.1.18:40000")), [1, 2]);
        assert_eq!(route(&one, a("10.0.0.5:8080")), [1, 2]);
        let two = [(1, a("127.0.0.1:8080")), (2, a("127.0.0.1:8081"))];
        assert_eq!(route(&two, a("127.0.0.1:8081")), [2]);
        assert_eq!(route(&two, a("127.0.0.1:8080")), [1]);
        assert!(
            route(&two, a("127.0.0.1:5555")).is_empty(),
            "same IP, unknown port: ambiguous"
        );
        let hosts = [(1, a("192.168.1.18:8080")), (2, a("192.168.1.19:8080"))];
        assert_eq!(route(&hosts, a("192.168.1.19:45000")), [2], "by IP");
        assert!(route(&hosts, a("192.168.1.20:8080")).is_empty());
        assert!(route(&[], a("192.168.1.20:8080")).is_empty());
    }
}
