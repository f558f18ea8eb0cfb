//! Realman arms (`kind: realman`): a controller speaking JSON over TCP with a UDP state push,
//! emulated in-process on in-memory streams (virtual or real time).

pub(crate) mod device;
pub mod model;
mod observe;
pub(crate) mod raw;
mod trace;
pub(crate) mod validate;

use std::sync::Arc;

pub use model::{
    RealmanAction as Action, RealmanSettings as Settings, RmCond as Check, RmFault as Fault,
};
pub use observe::Observation;

use super::{BusUse, Device, Drawing, FrameDecoder, KindSpec, RawKindStep, Wiring};
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use crate::wiring::Clock;
use device::RealmanDevice;

/// Whether a Realman emulator's physical state (joint angles and speeds) is finite.
pub(crate) fn realman_health(s: &sim::realman::firmware::ArmSnapshot) -> Result<(), String> {
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

/// The Realman kind's contract (registered in `crate::devices`).
pub(crate) struct Kind;

#[async_trait::async_trait]
impl KindSpec for Kind {
    const NAME: &'static str = "realman";
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
        fault.describe()
    }

    /// Every Realman action goes through the driver.
    fn action_needs_emulator(_action: &Action) -> Option<String> {
        None
    }

    /// A Realman arm is always emulated in-process (it is not a CAN device: `--iface` runs cannot
    /// reach it).
    fn in_process_requirements(_settings: &Settings, device: &str) -> Vec<String> {
        vec![format!(
            "the Realman arm `{device}` (TCP/UDP, not on a CAN interface)"
        )]
    }

    /// Start a Realman arm: the emulator on in-memory streams and the driver.
    async fn build(
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

    fn buses(_settings: &Settings, _at: Pos) -> Vec<BusUse> {
        // JSON over TCP and UDP: no CAN bus.
        Vec::new()
    }

    fn drawing(settings: &Settings) -> Option<Drawing> {
        Some(Drawing::arm(if settings.model.starts_with("RM75") {
            sim::realman::plant::RM75B_URDF
        } else {
            sim::realman::plant::RM65B_URDF
        }))
    }

    fn frame_decoder(_settings: &Settings, _buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
        // JSON over TCP and UDP: no CAN frames.
        None
    }
}

impl RawKindStep for raw::RawStep {
    fn id(&self) -> Option<&S<String>> {
        raw::RawStep::id(self)
    }
}
