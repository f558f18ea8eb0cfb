//! Where realtime-push datagrams go: a UDP socket in real time, an in-memory channel in virtual
//! time (no real I/O may run under a paused clock). Loss and reorder faults apply here.

use std::net::{IpAddr, SocketAddr};

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::net::UdpSocket;
use tokio::sync::mpsc;

/// One datagram as the emulator sent it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Datagram {
    /// Destination.
    pub to: SocketAddr,
    /// JSON text (no terminator: one object per datagram).
    pub payload: String,
}

/// The datagrams' way out.
#[derive(Debug)]
pub enum PushSink {
    /// A bound UDP socket.
    Udp(UdpSocket),
    /// An in-memory channel (virtual time).
    Channel(mpsc::UnboundedSender<Datagram>),
}

/// Loss / reorder settings and the state they need.
#[derive(Debug)]
pub struct PushFaults {
    /// Loss probability, ‰.
    pub loss_permille: u16,
    /// Swap consecutive datagrams.
    pub reorder: bool,
    held: Option<Datagram>,
    rng: SmallRng,
}

impl PushFaults {
    /// No faults; `seed` makes random loss reproducible.
    pub fn new(seed: u64) -> Self {
        Self {
            loss_permille: 0,
            reorder: false,
            held: None,
            rng: SmallRng::seed_from_u64(seed),
        }
    }

    /// Apply the faults to one datagram: what to send now, in order.
    pub fn apply(&mut self, datagram: Datagram) -> Vec<Datagram> {
        if self.loss_permille > 0 && self.rng.random_range(0..1000u16) < self.loss_permille {
            return Vec::new();
        }
        if !self.reorder {
            return self.held.take().into_iter().chain(Some(datagram)).collect();
        }
        match self.held.take() {
            Some(first) => vec![datagram, first],
            None => {
                self.held = Some(datagram);
                Vec::new()
            }
        }
    }
}

/// Counters of the push.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PushStats {
    /// Datagrams handed to the sink.
    pub sent: u64,
    /// Datagrams the sink refused (socket error, closed channel).
    pub failed: u64,
}

impl PushSink {
    /// Send one datagram; errors are counted, never fatal (UDP is best effort).
    pub async fn send(&self, datagram: Datagram, stats: &mut PushStats) {
        let ok = match self {
            Self::Udp(socket) => socket
                .send_to(datagram.payload.as_bytes(), datagram.to)
                .await
                .is_ok(),
            Self::Channel(tx) => tx.send(datagram).is_ok(),
        };
        if ok {
            stats.sent += 1;
        } else {
            stats.failed += 1;
            if stats.failed.is_power_of_two() {
                tracing::debug!(failed = stats.failed, "Realman push datagram not delivered");
            }
        }
    }
}

/// Where one push datagram goes, given the push's `ip` (empty: not set) and `port`, the peer
/// addresses of the TCP clients connected now, and whether the emulator listens on a
/// non-loopback address (`public`).
///
/// - No client connected: nowhere. Nobody is listening for the push then, and a target stored
///   by an earlier client (and kept across restarts by the state file) would otherwise get
///   ~200 datagrams/s for as long as the emulator runs.
/// - `ip` set, `public`: only if a connected client has that address. `set_realtime_push`
///   names any address and port, so without this check anyone who can reach the port could
///   aim the stream at a third machine.
/// - `ip` set, loopback (or in memory): that address (the UDP socket is bound to loopback, so
///   nothing leaves the machine).
/// - `ip` not set: every connected client's address, once per host.
pub fn targets(ip: &str, port: u16, clients: &[SocketAddr], public: bool) -> Vec<SocketAddr> {
    if clients.is_empty() {
        return Vec::new();
    }
    let mut hosts: Vec<IpAddr> = clients.iter().map(|c| c.ip().to_canonical()).collect();
    hosts.sort_unstable();
    hosts.dedup();
    match ip.parse::<IpAddr>() {
        Ok(ip) if !public || hosts.contains(&ip.to_canonical()) => {
            vec![SocketAddr::new(ip, port)]
        }
        Ok(_) => Vec::new(),
        Err(_) => hosts
            .into_iter()
            .map(|ip| SocketAddr::new(ip, port))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dg(n: u16) -> Datagram {
        Datagram {
            to: SocketAddr::from(([127, 0, 0, 1], n)),
            payload: n.to_string(),
        }
    }

    #[test]
    fn the_push_goes_only_to_connected_clients_on_a_public_bind() {
        let client: SocketAddr = "192.168.1.20:50000".parse().unwrap();
        let mapped: SocketAddr = "[::ffff:192.168.1.20]:50001".parse().unwrap();
        let to = |ip: &str| SocketAddr::new(ip.parse().unwrap(), 8089);
        // D7: a stored or requested third-party address gets nothing on a public bind.
        assert_eq!(targets("10.0.0.7", 8089, &[client], true), vec![]);
        assert_eq!(
            targets("192.168.1.20", 8089, &[client], true),
            vec![to("192.168.1.20")]
        );
        assert_eq!(
            targets("192.168.1.20", 8089, &[mapped], true),
            vec![to("192.168.1.20")],
            "an IPv4 client on a dual-stack socket is the same host"
        );
        // No client left: silence, whatever is configured.
        assert_eq!(targets("192.168.1.20", 8089, &[], true), vec![]);
        assert_eq!(targets("127.0.0.1", 8089, &[], false), vec![]);
        assert_eq!(targets("", 8089, &[], false), vec![]);
        // Loopback: the configured address, while a client is connected.
        assert_eq!(
            targets("10.0.0.7", 8089, &[client], false),
            vec![to("10.0.0.7")]
        );
        // No address set: every client host once.
        let second: SocketAddr = "192.168.1.20:50002".parse().unwrap();
        assert_eq!(
            targets("", 9000, &[client, second], true),
            vec![SocketAddr::new("192.168.1.20".parse().unwrap(), 9000)]
        );
    }

    #[test]
    fn reorder_swaps_pairs_and_loss_drops_some() {
        let mut f = PushFaults::new(1);
        f.reorder = true;
        let out: Vec<_> = (1..=4).flat_map(|n| f.apply(dg(n))).collect();
        assert_eq!(out, vec![dg(2), dg(1), dg(4), dg(3)]);
        let mut f = PushFaults::new(7);
        f.loss_permille = 500;
        let kept = (0..1000).flat_map(|n| f.apply(dg(n))).count();
        assert!((350..650).contains(&kept), "kept {kept} of 1000");
    }
}
