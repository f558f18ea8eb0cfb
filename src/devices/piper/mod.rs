//! The AgileX Piper arm (`kind: piper`): a CAN device on the bench's bus.

mod checks;
mod device;
mod emulator;
pub mod model;
mod observe;
pub(crate) mod raw;
mod trace;
pub(crate) mod validate;
pub mod vocab;
mod wire;

use std::sync::Arc;

use bus::CanBus;
use driver::piper::{PiperBuilder, Timeouts};

pub use model::{EmulatorFault as Fault, PiperAction as Action, PiperSettings as Settings};
pub use observe::Observation;
pub use validate::DEFAULT_FIRMWARE;

/// A Piper condition.
pub type Check = model::Check;

use super::Wiring;
use crate::harness::{Clock, Device, RunOptions, HOST_NODE};
use device::PiperDevice;
use emulator::PiperSim;

/// Short description of a fault for logs and reports.
pub fn describe_fault(fault: &Fault) -> String {
    fault.describe()
}

/// What a condition wants, for reports.
pub fn describe_check(check: &Check) -> String {
    checks::expected_text(check)
}

/// Piper actions all go through the driver; none needs the in-process emulator.
pub fn action_needs_emulator(_action: &Action) -> Option<String> {
    None
}

/// What `settings` need from the in-process emulator (a separate emulator process on a real
/// interface cannot be configured from the scenario).
pub fn in_process_requirements(settings: &Settings, device: &str) -> Vec<String> {
    let mut needs = Vec::new();
    if !settings.obstacles.is_empty() {
        needs.push(format!("obstacles on `{device}`"));
    }
    if settings.initial_joints_deg.iter().any(|a| *a != 0.0) {
        needs.push(format!("initial_joints_deg on `{device}`"));
    }
    if settings.gripper_max_mm.is_some() || settings.collision_levels.is_some() {
        needs.push(format!(
            "flash settings (gripper_max_mm, collision_levels) on `{device}`"
        ));
    }
    if settings.urdf.is_some() {
        needs.push(format!("urdf on `{device}`"));
    }
    needs
}

/// The driver's timeouts, scaled for slow real-time runs.
fn driver_timeouts(options: &RunOptions) -> Timeouts {
    let d = Timeouts::default();
    Timeouts {
        first_feedback: d.first_feedback.map(|t| options.deadline(t)),
        query: options.deadline(d.query),
        enable: options.deadline(d.enable),
        link: options.deadline(d.link),
        send: options.deadline(d.send),
        ..d
    }
}

/// Start a Piper: the emulator on the virtual bus (in-process runs) and the driver.
pub(crate) async fn build(
    name: &str,
    settings: &Settings,
    wiring: &Wiring<'_>,
) -> Result<Arc<dyn Device>, String> {
    match (wiring.bus, wiring.clock) {
        (Some(bus), _) => {
            let node: Arc<dyn CanBus> = Arc::new(bus.attach(name));
            let sim = PiperSim::spawn(node, settings)
                .map_err(|e| format!("device `{name}`: emulator: {e}"))?;
            let host: Arc<dyn CanBus> = Arc::new(bus.attach(HOST_NODE));
            let driver = PiperBuilder::new(host)
                .connect()
                .await
                .map_err(|e| format!("device `{name}`: driver could not connect: {e}"))?;
            Ok(Arc::new(PiperDevice::new(
                name,
                driver,
                Some(Box::new(sim)),
                *wiring.options,
            )))
        }
        (None, Clock::Iface(iface)) => {
            let host = crate::harness::bench::open_iface(iface, "driver")?;
            let driver = PiperBuilder::new(host)
                .timeouts(driver_timeouts(wiring.options))
                .connect()
                .await
                .map_err(|e| {
                    format!(
                        "device `{name}`: driver could not connect on {iface} (is `armhil sim piper --iface {iface}` running?): {e}"
                    )
                })?;
            Ok(Arc::new(PiperDevice::new(
                name,
                driver,
                None,
                *wiring.options,
            )))
        }
        (None, _) => Err(format!("device `{name}`: no bus to attach to")),
    }
}
