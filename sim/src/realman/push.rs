//! Where realtime-push datagrams go: a UDP socket in real time, an in-memory channel in virtual
//! time (no real I/O may run under a paused clock). Loss and reorder faults apply here.

use std::net::SocketAddr;

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
