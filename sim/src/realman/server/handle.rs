//! Starting an emulator on a transport, and the handle that connects clients to it, injects
//! faults and stops it.

use std::collections::BTreeMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use tokio::io::DuplexStream;
use tokio::net::{TcpListener, UdpSocket};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use super::connection::serve_connection;
use super::core_task::core_loop;
use super::fault_injection::{clear_fault, inject_fault};
use super::monitor::RealmanMonitor;
use super::tcp::accept_loop;
use super::{
    lock, EmulatorConfig, ServerError, ServerStats, Shared, Transport, WireFaults, DUPLEX_BYTES,
};
use crate::realman::faults::{FaultError, RealmanFault, RealmanFaultKind};
use crate::realman::firmware::{ArmSnapshot, Controller};
use crate::realman::params::StateFileError;
use crate::realman::push::{Datagram, PushFaults, PushSink};
use crate::supervise::{DeathWatch, Supervisor};

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
