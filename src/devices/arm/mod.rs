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

use super::{one_bus, BusUse, Device, Drawing, FrameDecoder, KindSpec, RawKindStep, Wiring};
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use crate::wiring::Clock;
use device::{ArmDevice, Emulator};

/// The vendor-neutral arm kind's contract (registered in `crate::devices`).
pub(crate) struct Kind;

#[async_trait::async_trait]
impl KindSpec for Kind {
    const NAME: &'static str = "arm";
    type Settings = Settings;
    type Action = Action;
    type Check = Check;
    type Fault = Fault;
    type RawSettings = raw::RawSettings;
    type RawStep = raw::RawStep;
    type RawConds = raw::RawConds;
    type RawFault = raw::RawFault;
    const CONDITION_KEYS: &'static [&'static str] = &raw::CONDITION_KEYS;

    fn validate_settings(ctx: &Ctx<'_>, raw: &raw::RawSettings, at: Pos) -> Res<Settings> {
        validate::settings(ctx, raw, at)
    }

    fn validate_step(
        ctx: &Ctx<'_>,
        raw: &raw::RawStep,
        at: Pos,
    ) -> Res<(&'static str, DeviceStep<Action>)> {
        validate::step(ctx, raw, at)
    }

    fn validate_checks(
        ctx: &Ctx<'_>,
        raw: &raw::RawConds,
        _device: usize,
        step: &str,
        at: Pos,
    ) -> Res<Vec<Check>> {
        validate::checks(ctx, raw, step, at)
    }

    fn validate_fault(
        ctx: &Ctx<'_>,
        raw: &raw::RawFault,
        _device: Option<usize>,
        at: Pos,
    ) -> Res<Fault> {
        validate::fault(ctx, raw, at)
    }

    /// What a condition wants, for reports.
    fn describe_check(check: &Check) -> String {
        check.expected_text()
    }

    /// Short description of a fault for logs and reports.
    fn describe_fault(fault: &Fault) -> String {
        fault.0.name().to_owned()
    }

    /// Every arm action goes through the Arm API.
    fn action_needs_emulator(_action: &Action) -> Option<String> {
        None
    }

    /// An arm of either vendor runs against its in-process emulator.
    fn in_process_requirements(settings: &Settings, device: &str) -> Vec<String> {
        vec![format!(
            "the {} arm `{device}` (`kind: arm` runs on the in-process emulators)",
            settings.vendor
        )]
    }

    /// Start the vendor's emulator and an Arm API object on our driver for it (not yet connected:
    /// scenarios call `connect` as users do).
    async fn build(
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
                    .bus()
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

    fn buses(settings: &Settings, at: Pos) -> Vec<BusUse> {
        match settings.vendor {
            Vendor::Piper => one_bus(&None, at),
            Vendor::Realman => Vec::new(),
        }
    }

    fn drawing(settings: &Settings) -> Option<Drawing> {
        Some(Drawing::arm(match settings.vendor {
            driver::arm::Vendor::Piper => sim::piper::BUNDLED_URDF,
            driver::arm::Vendor::Realman => sim::realman::plant::RM65B_URDF,
        }))
    }

    /// Its frames are the Piper's (a Realman speaks no CAN): decoded by the Piper's decoder,
    /// and without a scenario by `armhil decode --device piper`, which the `piper` kind
    /// registers (so this kind registers no `WIRE_DECODERS`).
    fn frame_decoder(settings: &Settings, _buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
        match settings.vendor {
            driver::arm::Vendor::Piper => Some(Arc::new(super::piper::decode::PiperFrames)),
            driver::arm::Vendor::Realman => None,
        }
    }
}

impl RawKindStep for raw::RawStep {
    fn id(&self) -> Option<&S<String>> {
        raw::RawStep::id(self)
    }
}

#[cfg(test)]
mod tests;
