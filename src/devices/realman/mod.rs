//! Realman arms (`kind: realman`): a controller speaking JSON over TCP with a UDP state push,
//! emulated in-process on in-memory streams (virtual or real time).

pub(crate) mod device;
pub mod model;
mod observe;
pub(crate) mod raw;
pub(crate) mod validate;

use std::sync::Arc;

pub use model::{
    RealmanAction as Action, RealmanSettings as Settings, RmCond as Check, RmFault as Fault,
};
pub use observe::Observation;

use super::Wiring;
use crate::harness::{Clock, Device};
use device::RealmanDevice;

/// Whether a Realman emulator's physical state (joint angles and speeds) is finite.
pub(crate) fn realman_health(s: &sim::realman::controller::ArmSnapshot) -> Result<(), String> {
    let angles = s
        .joints_rad
        .iter()
        .enumerate()
        .map(|(j, q)| (format!("joint {} angle", j + 1), *q));
    let speeds = s
        .speeds_rad_s
        .iter()
        .enumerate()
        .map(|(j, v)| (format!("joint {} speed", j + 1), *v));
    crate::devices::finite_state(angles.chain(speeds))
}

/// Short description of a fault for logs and reports.
pub fn describe_fault(fault: &Fault) -> String {
    fault.describe()
}

/// What a condition wants, for reports.
pub fn describe_check(check: &Check) -> String {
    check.expected_text()
}

/// Every Realman action goes through the driver.
pub fn action_needs_emulator(_action: &Action) -> Option<String> {
    None
}

/// A Realman arm is always emulated in-process (it is not a CAN device: `--iface` runs cannot
/// reach it).
pub fn in_process_requirements(_settings: &Settings, device: &str) -> Vec<String> {
    vec![format!(
        "the Realman arm `{device}` (TCP/UDP, not on a CAN interface)"
    )]
}

/// Start a Realman arm: the emulator on in-memory streams and the driver.
pub(crate) async fn build(
    name: &str,
    settings: &Settings,
    wiring: &Wiring<'_>,
) -> Result<Arc<dyn Device>, String> {
    if let Clock::Iface(iface) = wiring.clock {
        return Err(format!(
            "device `{name}`: a Realman arm speaks TCP/UDP, not CAN; it cannot run on {iface}"
        ));
    }
    Ok(Arc::new(RealmanDevice::start(name, settings).await?))
}
