//! A group of RobStride actuators addressed by joint name (`kind: actuator_group`): the
//! actuators of one limb on one bus, each driving its joint. Built on the RobStride emulator
//! and driver, and added through the device-kind contract alone (`KindSpec`): its folder and
//! one registration line.

mod device;
mod joints;
pub mod model;
pub(crate) mod raw;
pub(crate) mod validate;

#[cfg(test)]
mod tests;

use std::sync::Arc;
use std::time::Duration;

use bus::CanBus;

pub use model::{
    GroupAction as Action, GroupCheck as Check, GroupFault as Fault, GroupSettings as Settings,
};

use super::{
    one_bus, BaseColumns, BusUse, Device, Drawing, FirstOf, FrameDecoder, JointColumn, KindSpec,
    Posing, RawKindStep, Wiring,
};
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};
use device::GroupDevice;

/// How long the driver waits for each reply (before time scaling): the RobStride driver's.
const DRIVER_TIMEOUT: Duration = Duration::from_millis(20);

/// The actuator-group kind's contract.
pub(crate) struct Kind;

#[async_trait::async_trait]
impl KindSpec for Kind {
    const NAME: &'static str = "actuator_group";
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
        check.describe()
    }

    fn describe_fault(fault: &Fault) -> String {
        format!("{} on joint {}", fault.label, fault.joint)
    }

    fn action_needs_emulator(_action: &Action) -> Option<String> {
        None
    }

    fn in_process_requirements(_settings: &Settings, _device: &str) -> Vec<String> {
        Vec::new()
    }

    async fn build(
        name: &str,
        settings: &Settings,
        wiring: &Wiring<'_>,
    ) -> Result<Arc<dyn Device>, String> {
        let (hosts, emulator) = match (&settings.robot, wiring.bus()) {
            (Some(robot), Some(_)) => {
                let robot = device::spawn_robot(name, robot, &wiring.buses)
                    .map_err(|e| format!("device `{name}`: robot: {e}"))?;
                (robot.hosts, Some(robot.emulator))
            }
            (Some(_), None) => {
                return Err(format!(
                    "device `{name}`: a robot runs in process only (on the bench's virtual buses)"
                ))
            }
            (None, Some(bus)) => {
                let node: Arc<dyn CanBus> = Arc::new(bus.attach(name));
                let emulator = device::spawn_emulator(node, settings, wiring.bitrate_bps)
                    .map_err(|e| format!("device `{name}`: emulator: {e}"))?;
                let host = wiring.driver_bus(name).await?;
                (vec![host], Some(device::GroupEmulator::Rigs(emulator)))
            }
            (None, None) => (vec![wiring.driver_bus(name).await?], None),
        };
        let device = GroupDevice::start(
            name,
            settings,
            hosts,
            emulator,
            wiring.options.deadline(DRIVER_TIMEOUT),
        )?;
        Ok(Arc::new(device))
    }

    fn parts(settings: &Settings) -> Vec<String> {
        settings.actuators.iter().map(|a| a.joint.clone()).collect()
    }

    fn part_actuators(settings: &Settings) -> Vec<sim::actuator::ActuatorModel> {
        settings
            .actuators
            .iter()
            .map(|a| a.actuator.model())
            .collect()
    }

    fn buses(settings: &Settings, at: Pos) -> Vec<BusUse> {
        match &settings.robot {
            // A robot's buses are its file's, at their bit rates.
            Some(robot) => robot
                .buses
                .iter()
                .map(|b| BusUse {
                    name: Some(b.name.clone()),
                    bitrate_bps: Some(b.bitrate_bps),
                    data_bitrate_bps: b.data_bitrate_bps,
                    at,
                })
                .collect(),
            None => one_bus(&None, at),
        }
    }

    fn drawing(settings: &Settings) -> Option<Drawing> {
        // A group without a robot is a set of rigs: there is no model to draw.
        let robot = settings.robot.as_ref()?;
        let joints = robot
            .actuators
            .iter()
            .map(|a| JointColumn {
                column: device::joint_column(&a.joint),
                joint: a.joint.clone(),
                direction: if a.direction < 0.0 { -1.0 } else { 1.0 },
                offset_rad: a.zero_offset_rad,
            })
            .collect();
        let base = matches!(robot.base, sim::robot::Base::Floating { .. }).then_some(BaseColumns {
            position_m: [device::BASE_X, device::BASE_Y, device::BASE_HEIGHT],
            rpy_rad: [device::BASE_ROLL, device::BASE_PITCH, device::BASE_YAW],
        });
        Some(Drawing {
            urdf: robot.urdf.clone().into(),
            posed_by: Posing::Joints { joints, base },
            paths: Some(robot.urdf_paths.clone()),
        })
    }

    /// Its actuators' frames are their kinds' (RobStride's, Damiao's): without a scenario
    /// `armhil decode --device robstride|damiao` reads them, which those kinds register (so
    /// this kind registers no `WIRE_DECODERS`).
    fn frame_decoder(settings: &Settings, buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
        // Each actuator is known by its bus and ID (a robot's IDs repeat across its buses),
        // and decoded by its own kind's decoder with its own model.
        let actuators: Vec<_> = settings
            .actuators
            .iter()
            .map(|a| (buses.get(a.bus).cloned(), &a.actuator))
            .collect();
        Some(Arc::new(FirstOf(
            joints::KINDS.iter().map(|k| k.frames(&actuators)).collect(),
        )))
    }
}

impl RawKindStep for raw::RawStep {
    fn id(&self) -> Option<&S<String>> {
        raw::RawStep::id(self)
    }
}
