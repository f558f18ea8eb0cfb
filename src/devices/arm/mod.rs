//! Vendor-neutral arms (`kind: arm`): a device driven only through the Arm API
//! ([`driver::arm::ArmInterface`]), with the vendor's emulator in-process behind it. The vendor
//! comes from `vendor:` or from the file's `matrix: {vendor: [piper, realman]}`, so one
//! scenario runs once per vendor.

mod device;
pub mod model;
pub(crate) mod raw;
pub(crate) mod validate;

use std::sync::{Arc, Mutex};

use driver::arm::{ArmInterface, PiperArm, PiperArmOptions, RealmanArm, RealmanArmOptions, Vendor};

pub use model::{
    ArmAction as Action, ArmCond as Check, ArmFault as Fault, ArmSettings as Settings,
};

use super::Wiring;
use crate::harness::{Clock, Device};
use device::{ArmDevice, Emulator};

/// Short description of a fault for logs and reports.
pub fn describe_fault(fault: &Fault) -> String {
    fault.0.name().to_owned()
}

/// What a condition wants, for reports.
pub fn describe_check(check: &Check) -> String {
    check.expected_text()
}

/// Every arm action goes through the Arm API.
pub fn action_needs_emulator(_action: &Action) -> Option<String> {
    None
}

/// An arm of either vendor runs against its in-process emulator.
pub fn in_process_requirements(settings: &Settings, device: &str) -> Vec<String> {
    vec![format!(
        "the {} arm `{device}` (`kind: arm` runs on the in-process emulators)",
        settings.vendor
    )]
}

/// Start the vendor's emulator and an Arm API object on our driver for it (not yet connected:
/// scenarios call `connect` as users do).
pub(crate) async fn build(
    name: &str,
    settings: &Settings,
    wiring: &Wiring<'_>,
) -> Result<Arc<dyn Device>, String> {
    if let Clock::Iface(iface) = wiring.clock {
        return Err(format!(
            "device `{name}`: `kind: arm` runs on the in-process emulators, not on {iface}"
        ));
    }
    let (arm, emulator): (Arc<dyn ArmInterface>, Emulator) = match settings.vendor {
        Vendor::Piper => {
            let bus = wiring
                .bus
                .ok_or_else(|| format!("device `{name}`: no bus to attach the Piper to"))?;
            let (sim, piper) = super::piper::spawn_default(name, bus).await?;
            let arm = PiperArm::from_client(name, piper, PiperArmOptions::default());
            let emulator = Emulator::Piper {
                sim,
                bus: bus.faults(),
                cut: Mutex::new(None),
            };
            (Arc::new(arm), emulator)
        }
        Vendor::Realman => {
            use super::realman::device::{Emulated, HOST_IP, PUSH_PORT};
            let realman = super::realman::Settings {
                model: "RM65-B",
                initial_joints_deg: None,
                gripper: settings.gripper,
                clients: 1,
            };
            let emulated = Emulated::spawn(name, &realman).await?;
            let client = emulated.client(name).await?;
            let options = RealmanArmOptions {
                enable_gripper: settings.gripper,
                ..RealmanArmOptions::push_to(HOST_IP, PUSH_PORT, 5)
            };
            let arm = RealmanArm::from_client(name, client, emulated.feed, options);
            (
                Arc::new(arm),
                Emulator::Realman(Mutex::new(Some(emulated.emu))),
            )
        }
    };
    Ok(Arc::new(ArmDevice::new(name, arm, emulator)))
}

#[cfg(test)]
mod tests;
