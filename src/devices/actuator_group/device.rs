//! The group on a bench: the RobStride emulator with every actuator on one bus, or a robot
//! (in-process runs), and our driver of each actuator's kind with a handle per joint
//! (`joints`).

use std::sync::Arc;
use std::time::Duration;

use async_trait::async_trait;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use sim::fault_args::FaultArgs;
use sim::robot::{RobotEmulator, RobotHandle};
use sim::robstride::{
    Fault as MotorFault, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle,
};
use tokio::sync::Mutex;

use super::joints::{GroupJoint, JointError, Joints};
use super::model::{GroupAction, GroupActuator, GroupCheck, GroupFault, GroupSettings};
use crate::devices::{Action, Check, Device, DeviceError, DeviceFault, Reply, TraceColumn};
use crate::scenario::{ErrorClass, Signal};

/// Requests a group action keeps waiting on one bus at once (a host's CAN transmit queue
/// holds ten frames; a few stay free for the command streams).
const IN_FLIGHT_PER_BUS: usize = 8;

/// Quantum of traced angles (rad): a thousandth, so a wrong scale factor still shows.
const RAD_Q: f64 = 0.001;

/// Quantum of traced heights and positions (m): a millimetre.
const M_Q: f64 = 0.001;

/// The trace columns of a floating robot's root link pose (see `base_columns`); the report's
/// replay reads them by these names.
pub(crate) const BASE_X: &str = "base_x_m";
/// See [`BASE_X`].
pub(crate) const BASE_Y: &str = "base_y_m";
/// See [`BASE_X`].
pub(crate) const BASE_HEIGHT: &str = "base_height_m";
/// See [`BASE_X`].
pub(crate) const BASE_ROLL: &str = "base_roll_rad";
/// See [`BASE_X`].
pub(crate) const BASE_PITCH: &str = "base_pitch_rad";
/// See [`BASE_X`].
pub(crate) const BASE_YAW: &str = "base_yaw_rad";

/// The trace column of joint `joint`'s angle (its actuator's shaft angle).
pub(crate) fn joint_column(joint: &str) -> String {
    format!("{joint}_rad")
}

/// A floating robot's base columns: `joints` traces its height (what a fall shows), `pose`
/// where it is and how it lies, which the report's replay draws. Names and quanta.
fn base_columns(signals: &[Signal]) -> Vec<(&'static str, f64)> {
    let joints = signals.contains(&Signal::Joints);
    let pose = signals.contains(&Signal::Pose);
    let mut columns = Vec::new();
    if pose {
        columns.extend([(BASE_X, M_Q), (BASE_Y, M_Q)]);
    }
    if joints || pose {
        columns.push((BASE_HEIGHT, M_Q));
    }
    if pose {
        columns.extend([(BASE_ROLL, RAD_Q), (BASE_PITCH, RAD_Q), (BASE_YAW, RAD_Q)]);
    }
    columns
}

/// The value of base column `name` (one of [`base_columns`]'s) in `pose`.
fn base_value(pose: &sim::robot::BasePose, name: &str) -> f64 {
    match name {
        BASE_X => pose.position_m[0],
        BASE_Y => pose.position_m[1],
        BASE_HEIGHT => pose.position_m[2],
        BASE_ROLL => pose.rpy_rad[0],
        BASE_PITCH => pose.rpy_rad[1],
        _ => pose.rpy_rad[2],
    }
}

/// What answers for the group in an in-process run.
pub(crate) enum GroupEmulator {
    /// The RobStride emulator, every actuator on the bench's bus driving its own rig.
    Rigs(RobstrideHandle),
    /// A whole robot: one world, its actuators on its own buses.
    Robot(RobotHandle),
}

impl GroupEmulator {
    async fn inject(
        &self,
        actuator: &GroupActuator,
        fault: &str,
        args: &FaultArgs,
    ) -> Result<(), String> {
        match self {
            Self::Rigs(e) => {
                let (can_id, fault) = rig_fault(actuator, fault, args)?;
                e.inject(can_id, fault).await.map_err(|e| e.to_string())
            }
            Self::Robot(r) => r
                .inject(&actuator.joint, fault, args.clone())
                .await
                .map_err(|e| e.to_string()),
        }
    }

    async fn clear(
        &self,
        actuator: &GroupActuator,
        fault: &str,
        args: &FaultArgs,
    ) -> Result<(), String> {
        match self {
            Self::Rigs(e) => {
                let (can_id, fault) = rig_fault(actuator, fault, args)?;
                e.clear(can_id, fault).await.map_err(|e| e.to_string())
            }
            Self::Robot(r) => r
                .clear(&actuator.joint, fault, args.clone())
                .await
                .map_err(|e| e.to_string()),
        }
    }

    async fn shutdown(self) {
        match self {
            Self::Rigs(e) => e.shutdown().await,
            Self::Robot(r) => r.shutdown().await,
        }
    }
}

/// A bench rig's motor and the RobStride fault `fault` with `args` (a rig's actuators are
/// RobStride's; the scenario checked the fault against that table at load).
fn rig_fault(
    actuator: &GroupActuator,
    fault: &str,
    args: &FaultArgs,
) -> Result<(u8, MotorFault), String> {
    let motor = actuator
        .actuator
        .downcast_ref::<MotorConfig>()
        .ok_or_else(|| {
            format!(
                "joint `{}`: a rig's actuator is RobStride's",
                actuator.joint
            )
        })?;
    let fault = MotorFault::named(fault)
        .and_then(|f| f.with_values(args))
        .map_err(|e| e.message)?;
    Ok((motor.can_id, fault))
}

/// A `hold` command a stream repeats.
#[derive(Debug, Clone, Copy)]
struct Hold {
    angle_rad: f64,
    kp: f64,
    kd: f64,
}

/// A robot started for an in-process run.
pub(crate) struct SpawnedRobot {
    /// The hosts' nodes, one per bus in the robot's order.
    pub hosts: Vec<Arc<dyn CanBus>>,
    /// The robot.
    pub emulator: GroupEmulator,
}

/// A robot on the bench's virtual buses (one per robot bus, in the robot's order): the robot
/// and the host attached to each.
pub(crate) fn spawn_robot(
    name: &str,
    robot: &sim::robot::RobotConfig,
    buses: &[&VirtualBus],
) -> Result<SpawnedRobot, String> {
    if buses.len() != robot.buses.len() {
        return Err(format!(
            "the robot has {} buses, the bench gave it {}",
            robot.buses.len(),
            buses.len()
        ));
    }
    let nodes = buses
        .iter()
        .map(|b| Arc::new(b.attach(name)) as Arc<dyn CanBus>)
        .collect();
    let handle = RobotEmulator::spawn(robot.clone(), nodes).map_err(|e| e.to_string())?;
    let hosts = buses
        .iter()
        .map(|b| Arc::new(b.attach(crate::wiring::HOST_NODE)) as Arc<dyn CanBus>)
        .collect();
    Ok(SpawnedRobot {
        hosts,
        emulator: GroupEmulator::Robot(handle),
    })
}

/// The emulator answering for the group (in-process runs only).
pub(crate) fn spawn_emulator(
    node: Arc<dyn CanBus>,
    settings: &GroupSettings,
    bitrate_bps: u32,
) -> Result<RobstrideHandle, String> {
    let motors = settings
        .actuators
        .iter()
        .filter_map(|a| a.actuator.downcast_ref::<MotorConfig>().cloned())
        .collect();
    let mut config = RobstrideConfig::new(motors);
    config.bus_bitrate_bps = bitrate_bps;
    RobstrideBus::spawn(node, config).map_err(|e| e.to_string())
}

/// A group of actuators addressed by joint name.
pub(crate) struct GroupDevice {
    name: String,
    settings: GroupSettings,
    /// One handle per actuator, in settings order.
    motors: Vec<Arc<dyn GroupJoint>>,
    /// A robot's monitor (the base's position), when the group is a robot in process.
    robot: Option<sim::robot::RobotMonitor>,
    /// Each actuator's background command stream (`hold` with `every_ms`), if any.
    streams: std::sync::Mutex<Vec<Option<tokio::task::JoinHandle<()>>>>,
    /// The base's roll, pitch, yaw in the last trace row (rad), which the next row's angles
    /// stay near.
    last_rpy_rad: std::sync::Mutex<Option<[f64; 3]>>,
    /// The drivers behind the handles; keeps their receive tasks alive.
    _joints: Joints,
    emulator: Mutex<Option<GroupEmulator>>,
}

impl GroupDevice {
    /// The drivers' handles on `hosts` (one per bus of [`GroupSettings::buses`]), and the
    /// emulator when in-process.
    pub(crate) fn start(
        name: &str,
        settings: &GroupSettings,
        hosts: Vec<Arc<dyn CanBus>>,
        emulator: Option<GroupEmulator>,
        timeout: Duration,
    ) -> Result<Self, String> {
        let joints = Joints::start(name, &settings.actuators, hosts, timeout)?;
        let motors = joints.handles.clone();
        Ok(Self {
            name: name.to_owned(),
            settings: settings.clone(),
            streams: std::sync::Mutex::new(motors.iter().map(|_| None).collect()),
            last_rpy_rad: std::sync::Mutex::new(None),
            robot: match &emulator {
                Some(GroupEmulator::Robot(handle)) => Some(handle.monitor()),
                _ => None,
            },
            motors,
            _joints: joints,
            emulator: Mutex::new(emulator),
        })
    }

    /// The robot's monitor when the group is a robot whose base moves (a fixed base's height
    /// would be a constant column).
    fn floating_robot(&self) -> Option<&sim::robot::RobotMonitor> {
        let floating = self
            .settings
            .robot
            .as_ref()
            .is_some_and(|r| matches!(r.base, sim::robot::Base::Floating { .. }));
        self.robot.as_ref().filter(|_| floating)
    }

    fn joint(&self, index: usize) -> &str {
        &self.settings.actuators[index].joint
    }

    fn angle_rad(&self, index: usize) -> Option<f64> {
        self.motors[index].angle_rad()
    }

    /// Replace actuator `index`'s command stream by `command` sent every `period` (or by none).
    /// A failed send is not the stream's to report: the watchdog, the feedback and the
    /// scenario's checks see what a lost command did.
    fn stream(&self, index: usize, command: Option<(Hold, Duration)>) {
        let mut streams = self.streams.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(old) = streams[index].take() {
            old.abort();
        }
        if let Some((command, period)) = command {
            let motor = Arc::clone(&self.motors[index]);
            streams[index] = Some(tokio::spawn(async move {
                let mut ticks = tokio::time::interval(period);
                ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
                ticks.tick().await;
                loop {
                    ticks.tick().await;
                    let _ = motor.hold(command.angle_rad, command.kp, command.kd).await;
                }
            }));
        }
    }

    /// Stop every actuator's command stream.
    fn stop_streams(&self) {
        for index in 0..self.motors.len() {
            self.stream(index, None);
        }
    }

    /// Runs `each` on every motor at once, as a host driver does: one request outstanding
    /// per motor, the buses in parallel, at most [`IN_FLIGHT_PER_BUS`] requests waiting on
    /// one bus (a host's CAN transmit queue holds ten frames). A robot of 32 actuators on
    /// four buses enables in about 2 ms of bus time instead of 128 ms one motor at a time,
    /// its legs no longer unpowered while its arms are enabled. The first failure (in
    /// configuration order) names its joint.
    async fn on_every_motor<'a, F, Fut>(&'a self, each: F) -> Result<(), DeviceError>
    where
        F: Fn(&'a dyn GroupJoint) -> Fut,
        Fut: std::future::Future<Output = Result<(), JointError>>,
    {
        use futures::StreamExt;
        let each = &each;
        let buses = self.settings.buses.len().max(1);
        let per_bus = (0..buses).map(|bus| async move {
            let mut pending = futures::stream::FuturesUnordered::new();
            let mut failed = Vec::new();
            for (index, motor) in self.motors.iter().enumerate() {
                if self.settings.actuators[index].bus != bus {
                    continue;
                }
                if pending.len() == IN_FLIGHT_PER_BUS {
                    if let Some(done) = pending.next().await {
                        failed.extend(done);
                    }
                }
                let motor: &dyn GroupJoint = motor.as_ref();
                pending.push(async move { each(motor).await.err().map(|e| (index, e)) });
            }
            while let Some(done) = pending.next().await {
                failed.extend(done);
            }
            failed
        });
        let failures = futures::future::join_all(per_bus).await;
        match failures
            .into_iter()
            .flatten()
            .min_by_key(|(index, _)| *index)
        {
            Some((index, e)) => Err(self.error(index, e)),
            None => Ok(()),
        }
    }

    fn error(&self, index: usize, e: JointError) -> DeviceError {
        DeviceError::new(
            e.class,
            format!("joint `{}`: {}", self.joint(index), e.message),
        )
    }

    fn check(&self, check: &GroupCheck) -> Result<(), (String, String)> {
        match check {
            GroupCheck::Joints {
                targets,
                tolerance_rad,
            } => {
                for (name, target) in targets {
                    let actual = self.angle_rad(target.actuator);
                    let holds =
                        actual.is_some_and(|a| (a - target.angle_rad).abs() <= *tolerance_rad);
                    if !holds {
                        return Err((
                            format!("{name} {:.3} ±{tolerance_rad} rad", target.angle_rad),
                            match actual {
                                Some(a) => format!("{name} {a:.3} rad"),
                                None => format!("{name}: no feedback yet"),
                            },
                        ));
                    }
                }
                Ok(())
            }
            GroupCheck::BaseHeight {
                height_m,
                tolerance_m,
            } => {
                let Some(robot) = &self.robot else {
                    return Err((
                        check.describe(),
                        "no robot: a base height is a robot's (`robot:`, in process)".to_owned(),
                    ));
                };
                let actual = robot.base_position_m()[2];
                if (actual - height_m).abs() <= *tolerance_m {
                    Ok(())
                } else {
                    Err((check.describe(), format!("base height {actual:.3} m")))
                }
            }
            GroupCheck::EnabledJoints(want) => {
                // In the file's order, whatever order the check lists them in.
                let enabled: Vec<&str> = (0..self.motors.len())
                    .filter(|i| self.motors[*i].is_enabled())
                    .map(|i| self.joint(i))
                    .collect();
                let holds = enabled.len() == want.len()
                    && want.iter().all(|w| enabled.contains(&w.as_str()));
                if holds {
                    Ok(())
                } else {
                    Err((
                        check.describe(),
                        format!("enabled: [{}]", enabled.join(", ")),
                    ))
                }
            }
        }
    }

    fn group_fault<'f>(&self, fault: &'f DeviceFault) -> Result<&'f GroupFault, DeviceError> {
        match fault {
            DeviceFault::ActuatorGroup(f) => Ok(f),
            other => Err(DeviceError::unsupported(format!(
                "`{}` is not an actuator-group fault",
                other.describe()
            ))),
        }
    }
}

impl Drop for GroupDevice {
    fn drop(&mut self) {
        // A device dropped without `shutdown` (a failed bench build) leaves no stream behind.
        self.stop_streams();
    }
}

#[async_trait]
impl Device for GroupDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        _timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let Action::ActuatorGroup(action) = action else {
            return Err(DeviceError::unsupported(format!(
                "a {} action on actuator group `{}`",
                action.kind_name(),
                self.name
            )));
        };
        match action {
            GroupAction::Enable => {
                self.stop_streams();
                self.on_every_motor(|m| m.enable()).await?
            }
            GroupAction::Disable => {
                self.stop_streams();
                self.on_every_motor(|m| m.disable()).await?
            }
            GroupAction::Mode(mode) => {
                self.stop_streams();
                let mode = *mode;
                self.on_every_motor(|m| m.switch_mode(mode)).await?
            }
            GroupAction::Move {
                targets,
                speed_rad_s,
            } => {
                for target in targets {
                    self.stream(target.actuator, None);
                    self.motors[target.actuator]
                        .move_to(target.angle_rad, *speed_rad_s)
                        .await
                        .map_err(|e| self.error(target.actuator, e))?;
                }
            }
            GroupAction::ReleaseGantry => {
                let robot = self.floating_robot().ok_or_else(|| {
                    DeviceError::unsupported(format!(
                        "release_gantry: actuator group `{}` is not a robot with a floating base",
                        self.name
                    ))
                })?;
                let released = robot
                    .release_gantry()
                    .await
                    .map_err(|e| DeviceError::new(ErrorClass::Rejected, e.to_string()))?;
                if !released {
                    return Err(DeviceError::new(
                        ErrorClass::Rejected,
                        format!(
                            "release_gantry: nothing holds `{}`'s base: its gantry let go already, or it has none",
                            self.name
                        ),
                    ));
                }
            }
            GroupAction::Watchdog { window } => {
                let window = *window;
                self.on_every_motor(|m| m.watchdog(window)).await?
            }
            GroupAction::Hold {
                targets,
                kp,
                kd,
                every,
            } => {
                for target in targets {
                    let command = Hold {
                        angle_rad: target.angle_rad,
                        kp: *kp,
                        kd: *kd,
                    };
                    self.stream(target.actuator, None);
                    self.motors[target.actuator]
                        .hold(command.angle_rad, command.kp, command.kd)
                        .await
                        .map_err(|e| self.error(target.actuator, e))?;
                    self.stream(target.actuator, every.map(|period| (command, period)));
                }
            }
        }
        Ok(Reply::default())
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        for check in checks {
            match check {
                Check::ActuatorGroup(c) => self.check(c)?,
                other => {
                    return Err((
                        other.describe(),
                        "not an actuator-group condition".to_owned(),
                    ))
                }
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        let mut columns: Vec<TraceColumn> = Vec::new();
        if signals.contains(&Signal::Joints) {
            columns.extend(self.settings.actuators.iter().map(|a| TraceColumn {
                name: joint_column(&a.joint),
                quantum: RAD_Q,
                group: "angles",
            }));
        }
        if self.floating_robot().is_some() {
            columns.extend(
                base_columns(signals)
                    .into_iter()
                    .map(|(name, quantum)| TraceColumn {
                        name: name.to_owned(),
                        quantum,
                        group: "base",
                    }),
            );
        }
        columns
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        let mut row: Vec<Option<f64>> = Vec::new();
        if signals.contains(&Signal::Joints) {
            row.extend((0..self.motors.len()).map(|i| self.angle_rad(i)));
        }
        if let Some(robot) = self.floating_robot() {
            let mut pose = robot.base_pose();
            // Angles that run on through a fall instead of jumping by π or a turn.
            let mut last = self.last_rpy_rad.lock().unwrap_or_else(|e| e.into_inner());
            pose.rpy_rad = pose.rpy_near(last.unwrap_or([0.0; 3]));
            *last = Some(pose.rpy_rad);
            row.extend(
                base_columns(signals)
                    .into_iter()
                    .map(|(name, _)| Some(base_value(&pose, name))),
            );
        }
        row
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        let f = self.group_fault(fault)?;
        let actuator = &self.settings.actuators[f.actuator];
        match self.emulator.lock().await.as_ref() {
            Some(emulator) => emulator
                .inject(actuator, &f.fault, &f.args)
                .await
                .map_err(DeviceError::unsupported),
            None => Err(DeviceError::unsupported(
                "faults need the in-process emulator",
            )),
        }
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        let guard = self.emulator.lock().await;
        let Some(emulator) = guard.as_ref() else {
            return Err(DeviceError::unsupported(
                "faults need the in-process emulator",
            ));
        };
        let faults: Vec<(&GroupActuator, String, FaultArgs)> = match fault {
            Some(fault) => {
                let f = self.group_fault(fault)?;
                vec![(
                    &self.settings.actuators[f.actuator],
                    f.fault.clone(),
                    f.args.clone(),
                )]
            }
            // Every fault of every actuator's own table.
            None => self
                .settings
                .actuators
                .iter()
                .flat_map(|a| {
                    let model = a.actuator.model();
                    (a.actuator.kind().faults)(model.name)
                        .into_iter()
                        .map(move |f| (a, f.name.to_owned(), FaultArgs::new()))
                })
                .collect(),
        };
        for (actuator, fault, args) in faults {
            emulator
                .clear(actuator, &fault, &args)
                .await
                .map_err(DeviceError::unsupported)?;
        }
        Ok(())
    }

    async fn shutdown(&self) {
        self.stop_streams();
        if let Some(emulator) = self.emulator.lock().await.take() {
            emulator.shutdown().await;
        }
    }
}
