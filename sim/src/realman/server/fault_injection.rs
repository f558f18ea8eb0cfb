//! Faults the transport applies itself (reply delay, truncation, dropped connections, push
//! loss) and those it hands to the controller.

use std::time::Duration;

use super::connection::route_events;
use super::{lock, Shared};
use crate::realman::faults::{FaultError, RealmanFault, RealmanFaultKind};

/// Apply `fault` to the transport or the controller.
pub(super) fn inject_fault(shared: &Shared, fault: RealmanFault) -> Result<(), FaultError> {
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
pub(super) fn clear_fault(shared: &Shared, kind: RealmanFaultKind) {
    match kind {
        RealmanFaultKind::ConnectionDrop => {}
        RealmanFaultKind::ReplyDelay => lock(&shared.wire).reply_delay = None,
        RealmanFaultKind::MalformedReply => lock(&shared.wire).truncate_next = 0,
        RealmanFaultKind::UdpLoss => lock(&shared.push_faults).loss_permille = 0,
        RealmanFaultKind::UdpReorder => lock(&shared.push_faults).reorder = false,
        other => lock(&shared.core).clear(other),
    }
}
