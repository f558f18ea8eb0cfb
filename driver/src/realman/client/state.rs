//! The UDP realtime state stream, decoded and published.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

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
    task: JoinHandle<()>,
}

impl Drop for StateFeed {
    fn drop(&mut self) {
        self.task.abort();
    }
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
            task,
        }
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
