//! The AgileX Piper arm (`kind: piper`): a CAN device on the bench's bus.

pub(crate) mod decode;
pub(crate) mod device;
pub mod model;
mod observe;
pub(crate) mod raw;
mod trace;
pub(crate) mod validate;

use std::sync::Arc;

use bus::CanBus;
use driver::piper::{PiperBuilder, Timeouts};

pub use model::{PiperAction as Action, PiperSettings as Settings};
pub use observe::Observation;
/// A Piper emulator fault: the emulator's own type, named by [`sim::piper::FaultKind`].
pub use sim::piper::PiperFault as Fault;
pub use validate::DEFAULT_FIRMWARE;

/// A Piper condition.
pub type Check = model::Check;

use super::{
    one_bus, BusUse, Device, Drawing, FrameDecoder, KindSpec, RawKindStep, WireDecoder, Wiring,
};
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use crate::wiring::{Clock, RunOptions, HOST_NODE};
use device::checks;
use device::emulator::PiperSim;
use device::PiperDevice;

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

/// A Piper with the default settings (the default firmware, joints at zero) emulated on
/// `bus`, and our driver connected to it: how other kinds (the vendor-neutral `arm`) get one.
pub(crate) async fn spawn_default(
    name: &str,
    bus: &bus::virtual_bus::VirtualBus,
) -> Result<(Box<dyn device::EmulatorControl>, driver::piper::Piper), String> {
    let settings = Settings {
        bus: None,
        role: model::Role::Follower,
        firmware: DEFAULT_FIRMWARE.to_owned(),
        urdf: None,
        initial_joints_deg: [0.0; model::PIPER_JOINTS],
        gripper_max_mm: None,
        collision_levels: None,
        obstacles: Vec::new(),
    };
    let node: Arc<dyn CanBus> = Arc::new(bus.attach(name));
    let sim =
        PiperSim::spawn(node, &settings).map_err(|e| format!("device `{name}`: emulator: {e}"))?;
    let host: Arc<dyn CanBus> = Arc::new(bus.attach(HOST_NODE));
    let driver = PiperBuilder::new(host)
        .connect()
        .await
        .map_err(|e| format!("device `{name}`: driver could not connect: {e}"))?;
    Ok((Box::new(sim), driver))
}

/// The Piper kind's contract (registered in `crate::devices`).
pub(crate) struct Kind;

#[async_trait::async_trait]
impl KindSpec for Kind {
    const NAME: &'static str = "piper";
    type Settings = Settings;
    type Action = Action;
    type Check = Check;
    type Fault = Fault;
    type RawSettings = raw::RawSettings;
    type RawStep = raw::RawStep;
    type RawConds = raw::RawConds;
    type RawFault = raw::RawFault;
    const CONDITION_KEYS: &'static [&'static str] = &raw::CONDITION_KEYS;
    const WIRE_DECODERS: &'static [WireDecoder] = &[WireDecoder {
        name: "piper",
        help: "AgileX Piper (11-bit ids)",
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
        checks::expected_text(check)
    }

    /// Short description of a fault for logs and reports (the emulator's: `name joint N value`).
    fn describe_fault(fault: &Fault) -> String {
        fault.to_string()
    }

    /// Piper actions all go through the driver; none needs the in-process emulator.
    fn action_needs_emulator(_action: &Action) -> Option<String> {
        None
    }

    /// What `settings` need from the in-process emulator (a separate emulator process on a real
    /// interface cannot be configured from the scenario).
    fn in_process_requirements(settings: &Settings, device: &str) -> Vec<String> {
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

    /// Start a Piper: the emulator on the virtual bus (in-process runs) and the driver.
    async fn build(
        name: &str,
        settings: &Settings,
        wiring: &Wiring<'_>,
    ) -> Result<Arc<dyn Device>, String> {
        match (wiring.bus(), wiring.clock) {
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
                    wiring.options.clone(),
                )))
            }
            (None, Clock::Iface(link)) => {
                let host = link.open("driver").await?;
                let driver = PiperBuilder::new(host)
                    .timeouts(driver_timeouts(wiring.options))
                    .connect()
                    .await
                    .map_err(|e| {
                        format!(
                            "device `{name}`: driver could not connect on {link} (is `armhil sim piper {}` running?): {e}",
                            link.sim_option()
                        )
                    })?;
                Ok(Arc::new(PiperDevice::new(
                    name,
                    driver,
                    None,
                    wiring.options.clone(),
                )))
            }
            (None, _) => Err(format!("device `{name}`: no bus to attach to")),
        }
    }

    fn buses(settings: &Settings, at: Pos) -> Vec<BusUse> {
        one_bus(&settings.bus, at)
    }

    fn drawing(_settings: &Settings) -> Option<Drawing> {
        Some(Drawing::arm(sim::piper::BUNDLED_URDF))
    }

    fn frame_decoder(_settings: &Settings, _buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
        Some(Arc::new(decode::PiperFrames))
    }
}

impl RawKindStep for raw::RawStep {
    fn id(&self) -> Option<&S<String>> {
        raw::RawStep::id(self)
    }
}

#[cfg(test)]
mod tests {
    use sim::piper::FaultKind;

    /// The scenario guide's fault table is written by hand: it must name every fault of the
    /// emulator's table, with its parameters and their defaults.
    #[test]
    fn the_scenario_guide_lists_every_emulator_fault_with_its_parameters() {
        let guide = include_str!("../../../scenarios/README.md");
        let rows: Vec<&str> = guide
            .lines()
            .skip_while(|l| !l.starts_with("| Emulator fault |"))
            .take_while(|l| l.starts_with('|'))
            .collect();
        for kind in FaultKind::ALL {
            let name = format!("`{}`", kind.name());
            let row = rows
                .iter()
                .find(|r| r.split('|').nth(1).is_some_and(|c| c.contains(&name)))
                .unwrap_or_else(|| panic!("no row for {name} in scenarios/README.md"));
            let args = row.split('|').nth(2).unwrap_or_default();
            for p in kind.params() {
                assert!(args.contains(p.name), "{name}: `{}` not listed", p.name);
                if let Some(d) = p.default {
                    let shown = format!("`{}` ({d})", p.name);
                    assert!(args.contains(&shown), "{name}: default {shown} not shown");
                }
            }
            if kind.params().is_empty() {
                assert_eq!(args.trim(), "—", "{name} takes no arguments");
            }
        }
    }
}
