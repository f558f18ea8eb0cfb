//! A shared view of a running emulator: the web view and the harness read the controller
//! and the transport through it while clients are served.

use std::net::SocketAddr;
use std::sync::Arc;

use super::core_task::push_targets;
use super::fault_injection::{clear_fault, inject_fault};
use super::{lock, ServerStats, Shared};
use crate::realman::faults::{FaultError, RealmanFault, RealmanFaultKind};
use crate::realman::firmware::{ArmSnapshot, Controller};

/// A shared view of a running emulator, from [`RealmanHandle::monitor`](super::RealmanHandle::monitor).
#[derive(Clone)]
pub struct RealmanMonitor {
    pub(super) shared: Arc<Shared>,
}

impl std::fmt::Debug for RealmanMonitor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RealmanMonitor").finish_non_exhaustive()
    }
}

impl RealmanMonitor {
    /// See [`RealmanHandle::inject`](super::RealmanHandle::inject).
    pub fn inject(&self, fault: RealmanFault) -> Result<(), FaultError> {
        inject_fault(&self.shared, fault)
    }

    /// See [`RealmanHandle::clear`](super::RealmanHandle::clear).
    pub fn clear(&self, kind: RealmanFaultKind) {
        clear_fault(&self.shared, kind);
    }

    /// See [`RealmanHandle::snapshot`](super::RealmanHandle::snapshot).
    pub fn snapshot(&self) -> ArmSnapshot {
        lock(&self.shared.core).snapshot()
    }

    /// See [`RealmanHandle::with_controller`](super::RealmanHandle::with_controller).
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

    /// See [`RealmanHandle::stats`](super::RealmanHandle::stats).
    pub fn stats(&self) -> ServerStats {
        *lock(&self.shared.stats)
    }
}
