//! Damiao (DM) joint motors (`kind: damiao`): a bus of DM-J4310, DM-J4340, DM-J8009, …
//! motors on the bench's CAN bus, the emulator (`sim::damiao`) answering for every motor and
//! our driver (`driver::damiao`) as the host, one handle per motor. The protocol's own
//! decoder for `armhil decode --device damiao` lives here too ([`decode_damiao`]).

pub(crate) mod decode;
mod device;
pub mod model;
mod observe;
pub(crate) mod raw;
mod trace;
pub(crate) mod validate;

use std::sync::Arc;
use std::time::Duration;

pub use decode::{decode_damiao, DamiaoWireMotor};
pub use model::{
    DamiaoAction as Action, DamiaoSettings as Settings, DmFault as Fault, MotorCheck as Check,
};
pub use observe::{MotorObservation, Observation};

use super::contract::motor_bus::PER_MOTOR_CONDITION_KEYS;
use super::{
    one_bus, BusUse, Device, Drawing, FrameDecoder, KindSpec, RawKindStep, WireDecoder, Wiring,
};
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use device::DamiaoDevice;

/// How long the Damiao driver waits for each reply (its default, before time scaling).
const DRIVER_TIMEOUT: Duration = Duration::from_millis(20);

/// The Damiao kind's contract (registered in `crate::devices`).
pub(crate) struct Kind;

#[async_trait::async_trait]
impl KindSpec for Kind {
    const NAME: &'static str = "damiao";
    type Settings = Settings;
    type Action = Action;
    type Check = Check;
    type Fault = Fault;
    type RawSettings = raw::RawSettings;
    type RawStep = raw::RawStep;
    type RawConds = raw::RawConds;
    type RawFault = raw::RawFault;
    const CONDITION_KEYS: &'static [&'static str] = &PER_MOTOR_CONDITION_KEYS;
    const WIRE_DECODERS: &'static [WireDecoder] = &[WireDecoder {
        name: "damiao",
        help: "Damiao (DM) joint motors (11-bit ids; each motor by --motor ESC_ID:MODEL[:MST_ID], default 1:DM4310)",
        decoder: decode::wire,
    }];

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
        device: usize,
        step: &str,
        at: Pos,
    ) -> Res<Vec<Check>> {
        validate::checks(ctx, raw, device, step, at)
    }

    fn validate_fault(
        ctx: &Ctx<'_>,
        raw: &raw::RawFault,
        device: Option<usize>,
        at: Pos,
    ) -> Res<Fault> {
        validate::fault(ctx, raw, device, at)
    }

    fn describe_check(check: &Check) -> String {
        check.cond.expected_text(check.motor)
    }

    fn describe_fault(fault: &Fault) -> String {
        fault.describe()
    }

    fn action_needs_emulator(action: &Action) -> Option<String> {
        action
            .command
            .needs_emulator()
            .then(|| format!("damiao `{}`", action.command.name()))
    }

    /// Damiao settings are all the emulator's (motors, ids, models, loads), and a separate
    /// emulator process is configured on its own command line: none needs the in-process
    /// emulator.
    fn in_process_requirements(_settings: &Settings, _device: &str) -> Vec<String> {
        Vec::new()
    }

    /// Start a Damiao bus: the emulator on the virtual bus (in-process runs) and the driver.
    async fn build(
        name: &str,
        settings: &Settings,
        wiring: &Wiring<'_>,
    ) -> Result<Arc<dyn Device>, String> {
        Ok(Arc::new(DamiaoDevice::start(
            name,
            settings,
            wiring.driver_bus(name).await?,
            wiring.bus(),
            wiring.options.deadline(DRIVER_TIMEOUT),
        )?))
    }

    /// Its motors, by ESC_ID: what steps, conditions and faults name (`motor: 1`), checked
    /// when the file is read, with the device's motors listed when one is not there.
    fn parts(settings: &Settings) -> Vec<String> {
        settings
            .motors
            .iter()
            .map(|m| m.esc_id.to_string())
            .collect()
    }

    /// Each motor's model: whose fault thresholds and push limit a step or fault is checked by.
    fn part_actuators(settings: &Settings) -> Vec<sim::actuator::ActuatorModel> {
        settings
            .motors
            .iter()
            .map(|m| {
                sim::actuator::ActuatorSetup::model(&sim::damiao::MotorConfig::new(
                    m.esc_id, m.model,
                ))
            })
            .collect()
    }

    fn buses(settings: &Settings, at: Pos) -> Vec<BusUse> {
        one_bus(&settings.bus, at)
    }

    fn drawing(_settings: &Settings) -> Option<Drawing> {
        // A test rig of motors: no robot model to draw.
        None
    }

    fn frame_decoder(settings: &Settings, buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
        Some(Arc::new(decode::DamiaoFrames::new(settings, buses)))
    }
}

impl RawKindStep for raw::RawStep {
    fn id(&self) -> Option<&S<String>> {
        raw::RawStep::id(self)
    }
}

#[cfg(test)]
mod tests {
    use super::model::{MODES, STATES};
    use crate::devices::damiao::validate::step::COMMANDS;

    /// The scenario guide's Damiao section names every command, mode, state and emulator
    /// fault (each with its value), so it cannot fall behind the vocabulary.
    #[test]
    fn the_scenario_guide_lists_the_whole_vocabulary() {
        let guide = include_str!("../../../scenarios/README.md");
        let section: String = guide
            .lines()
            .skip_while(|l| !l.starts_with("## Damiao motors"))
            .skip(1)
            .take_while(|l| !l.starts_with("## "))
            .collect::<Vec<_>>()
            .join("\n");
        assert!(
            !section.is_empty(),
            "no Damiao section in scenarios/README.md"
        );
        let named = |word: &str| section.contains(&format!("`{word}`"));
        for (command, _, args) in COMMANDS {
            assert!(named(command), "do: {command} not in the guide");
            for arg in args {
                assert!(named(arg), "{command}'s `{arg}` not in the guide");
            }
        }
        for (_, mode) in MODES {
            assert!(named(mode), "mode {mode} not in the guide");
        }
        for (_, state) in STATES {
            assert!(named(state), "state {state} not in the guide");
        }
        let limits = sim::damiao::Thresholds::power_on(sim::damiao::Model::DM4310);
        for fault in sim::damiao::Fault::ALL {
            assert!(
                named(fault.name()),
                "fault {} not in the guide",
                fault.name()
            );
            for p in fault.info(&limits).params {
                assert!(
                    named(p.name),
                    "{}'s `{}` not in the guide",
                    fault.name(),
                    p.name
                );
            }
        }
    }
}
