//! RobStride actuators (`kind: robstride`): a bus of motors on the bench's CAN bus.

pub(crate) mod decode;
mod device;
pub mod model;
mod observe;
pub(crate) mod raw;
mod trace;
pub(crate) mod validate;

use std::sync::Arc;
use std::time::Duration;

pub use model::{
    MotorCheck as Check, RobstrideAction as Action, RobstrideSettings as Settings, RsFault as Fault,
};
pub use observe::{MotorObservation, Observation};

use super::contract::motor_bus::PER_MOTOR_CONDITION_KEYS;
use super::{
    one_bus, BusUse, Device, Drawing, FrameDecoder, KindSpec, RawKindStep, WireDecoder, Wiring,
};
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use device::RobstrideDevice;

/// How long the RobStride driver waits for each reply (its default, before time scaling).
const DRIVER_TIMEOUT: Duration = Duration::from_millis(20);

/// The RobStride kind's contract (registered in `crate::devices`).
pub(crate) struct Kind;

#[async_trait::async_trait]
impl KindSpec for Kind {
    const NAME: &'static str = "robstride";
    type Settings = Settings;
    type Action = Action;
    type Check = Check;
    type Fault = Fault;
    type RawSettings = raw::RawSettings;
    type RawStep = raw::RawStep;
    type RawConds = raw::RawConds;
    type RawFault = raw::RawFault;
    const CONDITION_KEYS: &'static [&'static str] = &PER_MOTOR_CONDITION_KEYS;
    const WIRE_DECODERS: &'static [WireDecoder] = &[
        WireDecoder {
            name: "robstride",
            help: "RobStride actuators (29-bit ids, private protocol)",
            decoder: decode::wire_private,
        },
        WireDecoder {
            name: "robstride-mit",
            help: "RobStride actuators switched to the MIT variant (11-bit ids)",
            decoder: decode::wire_mit,
        },
    ];

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
        check.cond.expected_text(check.motor)
    }

    /// Short description of a fault for logs and reports.
    fn describe_fault(fault: &Fault) -> String {
        fault.describe()
    }

    /// Why an action needs the in-process emulator, if it does.
    fn action_needs_emulator(action: &Action) -> Option<String> {
        action
            .command
            .needs_emulator()
            .then(|| format!("robstride `{}`", action.command.name()))
    }

    /// RobStride settings are all the emulator's (motors, models, loads), and a separate emulator
    /// process is configured on its own command line: none needs the in-process emulator.
    fn in_process_requirements(_settings: &Settings, _device: &str) -> Vec<String> {
        Vec::new()
    }

    /// Start a RobStride bus: the emulator on the virtual bus (in-process runs) and the driver.
    async fn build(
        name: &str,
        settings: &Settings,
        wiring: &Wiring<'_>,
    ) -> Result<Arc<dyn Device>, String> {
        Ok(Arc::new(RobstrideDevice::start(
            name,
            settings,
            wiring.driver_bus(name).await?,
            wiring.bus(),
            wiring.bitrate_bps,
            wiring.options.deadline(DRIVER_TIMEOUT),
        )?))
    }

    fn buses(settings: &Settings, at: Pos) -> Vec<BusUse> {
        one_bus(&settings.bus, at)
    }

    fn drawing(_settings: &Settings) -> Option<Drawing> {
        // A test rig of motors, drawn as dials from their angle columns.
        None
    }

    fn frame_decoder(settings: &Settings, buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
        Some(Arc::new(decode::RobstrideFrames::new(settings, buses)))
    }
}

impl RawKindStep for raw::RawStep {
    fn id(&self) -> Option<&S<String>> {
        raw::RawStep::id(self)
    }
}
