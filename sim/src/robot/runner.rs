//! The task that runs a whole robot: every actuator's firmware, one physics world, every bus;
//! and the handle the harness and `armhil sim robot` hold.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use bus::{CanBus, CanFrame, ReceivedFrame};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use super::base_pose::BasePose;
use super::config::{Gantry, RobotConfig, RobotConfigError};
use super::world::{RobotWorld, RobotWorldError};
use crate::actuator::{deliver, ActuatorConfig, ActuatorFirmware, ActuatorSnapshot, PowerOn};
use crate::can_runner::{receive_frames, StepClock, TxBacklog};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::physics::PhysicsError;
use crate::robot::faults::RobotLayout;
use crate::robstride::faults::{check_temperature_c, within, ValueError};
use crate::robstride::state_file::{StateFile, StateFileError};
use crate::supervise::{DeathWatch, Supervisor};

/// Harness requests waiting for the runner.
const REQUEST_QUEUE: usize = 64;

/// Why a robot could not start or a request failed.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The configuration is inconsistent.
    #[error(transparent)]
    Config(#[from] RobotConfigError),
    /// The URDF or a joint name did not load.
    #[error(transparent)]
    World(#[from] RobotWorldError),
    /// `spawn` got another number of buses than the configuration has.
    #[error("the robot has {expected} buses but {given} were given to serve them")]
    BusCount {
        /// Buses in the configuration.
        expected: usize,
        /// Buses given.
        given: usize,
    },
    /// No actuator drives a joint of this name.
    #[error("no actuator drives joint `{joint}`")]
    UnknownJoint {
        /// The name asked for.
        joint: String,
    },
    /// The robot has no bus of this name.
    #[error("the robot has no bus `{bus}`")]
    UnknownBus {
        /// The name asked for.
        bus: String,
    },
    /// A temperature or torque that is not finite or out of range.
    #[error("joint `{joint}`: {source}")]
    BadValue {
        /// The joint.
        joint: String,
        /// What is wrong.
        source: ValueError,
    },
    /// The actuator's kind has no such fault, or refused its arguments.
    #[error("joint `{joint}`: {source}")]
    Fault {
        /// The joint.
        joint: String,
        /// What is wrong.
        source: FaultArgError,
    },
    /// The state file could not be read or written.
    #[error(transparent)]
    StateFile(#[from] StateFileError),
    /// The state file would put two actuators of one bus on one CAN ID (a host moved one
    /// there in an earlier run).
    #[error("bus `{bus}`: {clash}")]
    IdClash {
        /// The bus.
        bus: String,
        /// Both actuators, the ID and the file.
        clash: Box<crate::robstride::state_file::IdClash>,
    },
    /// The state file would put two actuators of one bus on one CAN ID, found through their
    /// kinds' own kept settings (any kind; RobStride's clash is told in more detail by
    /// [`RobotError::IdClash`] first).
    #[error(
        "bus `{bus}`: joints `{}` and `{}` would both power on with CAN ID {id} (0x{id:X}): the \
         state file {} keeps one of them there (a host moved it and saved). Edit or delete that \
         actuator's entry in the file",
        joints[0], joints[1], state_file.display()
    )]
    PowerOnIdClash {
        /// The bus.
        bus: String,
        /// The ID both would answer on.
        id: u32,
        /// Both joints, in robot-file order.
        joints: [String; 2],
        /// The state file.
        state_file: std::path::PathBuf,
    },
    /// The emulator task has stopped.
    #[error("the robot emulator has stopped")]
    Stopped,
}

/// One actuated joint's state.
#[derive(Debug, Clone, PartialEq)]
pub struct JointSnapshot {
    /// The URDF joint.
    pub joint: String,
    /// The bus its actuator is on.
    pub bus: String,
    /// Joint position in the world (rad).
    pub position_rad: f64,
    /// Joint speed in the world (rad/s).
    pub velocity_rad_s: f64,
    /// The actuator's own view (its shaft angle is after direction and zero offset).
    pub actuator: ActuatorSnapshot,
}

/// The whole robot's state.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotSnapshot {
    /// Emulated time since power-on (s).
    pub time_s: f64,
    /// Position of the URDF root link's origin in the world (m).
    pub base_position_m: [f64; 3],
    /// Orientation of the URDF root link in the world, a rotation matrix by rows (identity
    /// for a fixed base; a fallen humanoid's is far from it).
    pub base_rotation: [[f64; 3]; 3],
    /// Every actuated joint, in configuration order.
    pub joints: Vec<JointSnapshot>,
    /// The buses currently cut off (a `bus_lost` fault).
    pub lost_buses: Vec<String>,
    /// Whether a stand still holds the base ([`crate::robot::Gantry`]).
    pub gantry_holds: bool,
}

impl RobotSnapshot {
    /// The joint of this name.
    pub fn joint(&self, name: &str) -> Option<&JointSnapshot> {
        self.joints.iter().find(|j| j.joint == name)
    }
}

enum Request {
    Inject(Addressed, oneshot::Sender<Result<(), RobotError>>),
    RemoveCause(Addressed, oneshot::Sender<Result<(), RobotError>>),
    SetTemperature(String, f64, oneshot::Sender<Result<(), RobotError>>),
    SetExternalTorque(String, f64, oneshot::Sender<Result<(), RobotError>>),
    SetBusLost(String, bool, oneshot::Sender<Result<(), RobotError>>),
    Snapshot(oneshot::Sender<RobotSnapshot>),
    ReleaseGantry(oneshot::Sender<bool>),
    Shutdown(oneshot::Sender<()>),
}

/// A fault of the actuator of a joint: its name in the actuator kind's table, and arguments.
struct Addressed {
    joint: String,
    fault: String,
    args: FaultArgs,
}

/// Emulated robots.
#[derive(Debug)]
pub struct RobotEmulator;

/// The harness's handle on a running robot.
#[derive(Debug)]
pub struct RobotHandle {
    view: RobotMonitor,
    task: Option<JoinHandle<()>>,
    death: DeathWatch,
}

/// A cloneable view of a running robot (snapshots and faults), for monitors.
#[derive(Debug, Clone)]
pub struct RobotMonitor {
    requests: mpsc::Sender<Request>,
    /// The root link's pose after the latest step (read without asking the runner, so a
    /// scenario's synchronous checks and its trace can see it).
    base: Arc<std::sync::Mutex<BasePose>>,
    /// Its joints and buses by name, which its faults are addressed by.
    layout: Arc<RobotLayout>,
}

impl RobotEmulator {
    /// Power the robot on and serve `buses` (one per [`RobotConfig::buses`], same order).
    /// Spawns on the current runtime; works under a paused clock (virtual time).
    pub fn spawn(
        config: RobotConfig,
        buses: Vec<Arc<dyn CanBus>>,
    ) -> Result<RobotHandle, RobotError> {
        config.check()?;
        if buses.len() != config.buses.len() {
            return Err(RobotError::BusCount {
                expected: config.buses.len(),
                given: buses.len(),
            });
        }
        let state = match &config.state_file {
            Some(path) => StateFile::load(path)?,
            None => StateFile::default(),
        };
        check_kept_ids(&config, &state)?;
        let (world, plants) = RobotWorld::new(&config)?;
        let mut actuators = Vec::with_capacity(plants.len());
        for (spec, plant) in config.actuators.iter().zip(plants) {
            let how = PowerOn {
                bus: &config.buses[spec.bus].name,
                bitrate_bps: config.buses[spec.bus].bitrate_bps,
                host_id: config.host_id,
                kept: &state,
            };
            let mut firmware = spec.actuator.power_on(Box::new(plant), &how);
            // The world steps once per tick for every joint (see `joint_plant`).
            firmware.set_control_substeps(1);
            actuators.push(JointActuator {
                joint: spec.joint.clone(),
                bus: spec.bus,
                config: spec.actuator.clone(),
                firmware,
            });
        }
        let ports = config
            .buses
            .iter()
            .zip(buses)
            .map(|(b, bus)| Port {
                name: b.name.clone(),
                bus,
                lost: false,
                backlog: TxBacklog::default(),
            })
            .collect();
        let (requests, inbox) = mpsc::channel(REQUEST_QUEUE);
        let base = Arc::new(std::sync::Mutex::new(base_pose(&world)));
        let layout = Arc::new(RobotLayout {
            joints: config
                .actuators
                .iter()
                .map(|a| (a.joint.clone(), a.actuator.model()))
                .collect(),
            buses: config.buses.iter().map(|b| b.name.clone()).collect(),
        });
        let runner = Runner {
            ports,
            actuators,
            world,
            state,
            state_path: config.state_file,
            base: Arc::clone(&base),
            gantry: config.gantry,
        };
        let (supervisor, death) = Supervisor::new();
        let task = supervisor.spawn(
            &tokio::runtime::Handle::current(),
            "robot runner",
            runner.run(inbox),
        );
        Ok(RobotHandle {
            view: RobotMonitor {
                requests,
                base,
                layout,
            },
            task: Some(task),
            death,
        })
    }
}

impl RobotMonitor {
    /// Position of the URDF root link's origin in the world after the latest step (m): a
    /// floating robot's pelvis height is its `[2]`.
    pub fn base_position_m(&self) -> [f64; 3] {
        self.base_pose().position_m
    }

    /// Its actuated joints and buses by name, in configuration order.
    pub fn layout(&self) -> &RobotLayout {
        &self.layout
    }

    /// Pose of the URDF root link in the world after the latest step.
    pub fn base_pose(&self) -> BasePose {
        *self.base.lock().unwrap_or_else(|e| e.into_inner())
    }

    async fn ask<T>(
        &self,
        make: impl FnOnce(oneshot::Sender<T>) -> Request,
    ) -> Result<T, RobotError> {
        let (reply, answer) = oneshot::channel();
        self.requests
            .send(make(reply))
            .await
            .map_err(|_| RobotError::Stopped)?;
        answer.await.map_err(|_| RobotError::Stopped)
    }

    /// Inject the fault `fault` of the actuator kind's table (with `args`, its values) into
    /// the actuator of `joint`.
    pub async fn inject(
        &self,
        joint: &str,
        fault: &str,
        args: FaultArgs,
    ) -> Result<(), RobotError> {
        let addressed = Addressed::new(joint, fault, args);
        self.ask(|reply| Request::Inject(addressed, reply)).await?
    }

    /// Remove a fault's cause; the latched fault stays until the host clears it.
    pub async fn clear(&self, joint: &str, fault: &str, args: FaultArgs) -> Result<(), RobotError> {
        let addressed = Addressed::new(joint, fault, args);
        self.ask(|reply| Request::RemoveCause(addressed, reply))
            .await?
    }

    /// Set the winding temperature (°C) of `joint`'s actuator.
    pub async fn set_temperature(&self, joint: &str, celsius: f64) -> Result<(), RobotError> {
        self.ask(|reply| Request::SetTemperature(joint.to_owned(), celsius, reply))
            .await?
    }

    /// Push `joint` with an external torque (N·m, shaft frame) until changed.
    pub async fn set_external_torque(&self, joint: &str, torque_nm: f64) -> Result<(), RobotError> {
        self.ask(|reply| Request::SetExternalTorque(joint.to_owned(), torque_nm, reply))
            .await?
    }

    /// Cut a bus off (`lost = true`: no frame reaches its actuators, none leaves them) or
    /// restore it.
    pub async fn set_bus_lost(&self, bus: &str, lost: bool) -> Result<(), RobotError> {
        self.ask(|reply| Request::SetBusLost(bus.to_owned(), lost, reply))
            .await?
    }

    /// The robot's state now.
    pub async fn snapshot(&self) -> Result<RobotSnapshot, RobotError> {
        self.ask(Request::Snapshot).await
    }

    /// Lets the stand go of the base (see [`crate::robot::Gantry`]): from then on the robot
    /// stands or falls. `false` when nothing held it.
    pub async fn release_gantry(&self) -> Result<bool, RobotError> {
        self.ask(Request::ReleaseGantry).await
    }
}

impl RobotHandle {
    /// A cloneable view for monitors; its calls fail with [`RobotError::Stopped`] once the
    /// robot is shut down.
    pub fn monitor(&self) -> RobotMonitor {
        self.view.clone()
    }

    /// See [`RobotMonitor::inject`].
    pub async fn inject(
        &self,
        joint: &str,
        fault: &str,
        args: FaultArgs,
    ) -> Result<(), RobotError> {
        self.view.inject(joint, fault, args).await
    }

    /// See [`RobotMonitor::clear`].
    pub async fn clear(&self, joint: &str, fault: &str, args: FaultArgs) -> Result<(), RobotError> {
        self.view.clear(joint, fault, args).await
    }

    /// See [`RobotMonitor::set_temperature`].
    pub async fn set_temperature(&self, joint: &str, celsius: f64) -> Result<(), RobotError> {
        self.view.set_temperature(joint, celsius).await
    }

    /// See [`RobotMonitor::set_external_torque`].
    pub async fn set_external_torque(&self, joint: &str, torque_nm: f64) -> Result<(), RobotError> {
        self.view.set_external_torque(joint, torque_nm).await
    }

    /// See [`RobotMonitor::set_bus_lost`].
    pub async fn set_bus_lost(&self, bus: &str, lost: bool) -> Result<(), RobotError> {
        self.view.set_bus_lost(bus, lost).await
    }

    /// See [`RobotMonitor::snapshot`].
    pub async fn snapshot(&self) -> Result<RobotSnapshot, RobotError> {
        self.view.snapshot().await
    }

    /// A watch that tells when the robot stops on its own (a panic, a state file that cannot
    /// be written, physics that diverged).
    pub fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Power the robot off; persistent state is already on disk.
    pub async fn shutdown(mut self) {
        let _ = self.view.ask(Request::Shutdown).await;
        if let Some(task) = self.task.take() {
            let _ = task.await;
        }
    }
}

impl Drop for RobotHandle {
    fn drop(&mut self) {
        if let Some(task) = self.task.take() {
            task.abort();
        }
    }
}

impl Addressed {
    fn new(joint: &str, fault: &str, args: FaultArgs) -> Self {
        Self {
            joint: joint.to_owned(),
            fault: fault.to_owned(),
            args,
        }
    }
}

struct JointActuator {
    joint: String,
    bus: usize,
    /// What it was configured as (where its kept state goes).
    config: ActuatorConfig,
    firmware: Box<dyn ActuatorFirmware>,
}

struct Port {
    name: String,
    bus: Arc<dyn CanBus>,
    lost: bool,
    /// Frames the bus's full transmit queue refused, sent first at the next chance.
    backlog: TxBacklog,
}

struct Runner {
    ports: Vec<Port>,
    actuators: Vec<JointActuator>,
    world: RobotWorld,
    state: StateFile,
    state_path: Option<PathBuf>,
    /// Shared with the monitors: the root link's pose after the latest step.
    base: Arc<std::sync::Mutex<BasePose>>,
    /// When the stand lets go of the base.
    gantry: Gantry,
}

/// Refuses a state file that would put two actuators of one bus on one CAN ID (a host moved
/// one onto another's in an earlier run), naming both joints, the bus, the ID and the file:
/// the robot's actuators keep their IDs in the same state file as a RobStride bus's motors,
/// and are refused for the same reason (see `RobstrideBus::spawn`).
pub fn check_kept_ids(config: &RobotConfig, kept: &StateFile) -> Result<(), RobotError> {
    let Some(path) = &config.state_file else {
        return Ok(());
    };
    for (k, bus) in config.buses.iter().enumerate() {
        // RobStride's own check first: it names the kept entries.
        let on_bus = config
            .actuators
            .iter()
            .filter(|a| a.bus == k)
            .filter_map(|a| {
                let motor = a.actuator.downcast_ref::<crate::robstride::MotorConfig>()?;
                let name = format!(
                    "joint `{}` (motor {}:{})",
                    a.joint,
                    motor.can_id,
                    motor.model.name()
                );
                Some((name, motor))
            });
        if let Some(clash) = kept.id_clash(path, on_bus) {
            return Err(RobotError::IdClash {
                bus: bus.name.clone(),
                clash: Box::new(clash),
            });
        }
        // Every kind: the ID each actuator powers on with, its kept settings applied.
        let mut powered: Vec<(u32, &str)> = Vec::new();
        for a in config.actuators.iter().filter(|a| a.bus == k) {
            let id = a.actuator.power_on_id(&bus.name, kept);
            if let Some((_, other)) = powered.iter().find(|(seen, _)| *seen == id) {
                return Err(RobotError::PowerOnIdClash {
                    bus: bus.name.clone(),
                    id,
                    joints: [(*other).to_owned(), a.joint.clone()],
                    state_file: path.clone(),
                });
            }
            powered.push((id, &a.joint));
        }
    }
    Ok(())
}

/// Pose of the URDF root link (the tree's root, wherever the file lists it) in the world.
fn base_pose(world: &RobotWorld) -> BasePose {
    let world = world.world();
    world
        .link_pose(world.model().root_link_name())
        .map_or_else(BasePose::default, |pose| BasePose::of(&pose))
}

/// Orientation of the URDF root link in the world (rotation matrix, by rows).
fn base_rotation(world: &RobotWorld) -> [[f64; 3]; 3] {
    let world = world.world();
    let rotation = world
        .link_pose(world.model().root_link_name())
        .map(|pose| pose.rotation.to_rotation_matrix().into_inner());
    match rotation {
        Some(m) => std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])),
        None => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    }
}

impl Runner {
    async fn run(mut self, mut inbox: mpsc::Receiver<Request>) -> Result<(), String> {
        let buses = self
            .ports
            .iter()
            .map(|port| (Arc::clone(&port.bus), port.name.clone()))
            .collect();
        let (mut frames, receivers) = receive_frames(buses, "robot");
        let mut clock = StepClock::start("robot-clock");
        let outcome = loop {
            tokio::select! {
                biased;
                request = inbox.recv() => match request {
                    Some(Request::Shutdown(done)) => {
                        let _ = done.send(());
                        break Ok(());
                    }
                    Some(request) => self.serve(request).await,
                    None => break Ok(()),
                },
                // Time before frames: a host flooding the buses must not stop the clock
                // (frames arriving faster than they are handled would starve the tick).
                steps = clock.next() => {
                    if steps.dropped > 0 {
                        tracing::debug!(dropped = steps.dropped, "robot emulator: steps dropped behind the wall clock");
                    }
                    let mut failed = None;
                    for _ in 0..steps.run {
                        if let Err(error) = self.on_tick().await {
                            failed = Some(error);
                            break;
                        }
                    }
                    if let Some(error) = failed {
                        break Err(error.to_string());
                    }
                }
                frame = frames.recv() => match frame {
                    Some((port, frame)) => {
                        if let Err(error) = self.on_frame(port, &frame).await {
                            break Err(error.to_string());
                        }
                    }
                    None => break Ok(()),
                },
            }
        };
        for receiver in receivers {
            receiver.abort();
        }
        outcome
    }

    fn actuator_mut(&mut self, joint: &str) -> Result<&mut JointActuator, RobotError> {
        self.actuators
            .iter_mut()
            .find(|a| a.joint == joint)
            .ok_or_else(|| RobotError::UnknownJoint {
                joint: joint.to_owned(),
            })
    }

    async fn serve(&mut self, request: Request) {
        match request {
            Request::Inject(at, reply) => {
                let result = self.actuator_mut(&at.joint).and_then(|a| {
                    let frames = a.firmware.inject(&at.fault, &at.args);
                    let frames = frames.map_err(|source| RobotError::Fault {
                        joint: at.joint.clone(),
                        source,
                    })?;
                    Ok((a.bus, frames))
                });
                let result = match result {
                    Ok((bus, frames)) => {
                        self.send(bus, frames).await;
                        Ok(())
                    }
                    Err(error) => Err(error),
                };
                let _ = reply.send(result);
            }
            Request::RemoveCause(at, reply) => {
                let result = self.actuator_mut(&at.joint).and_then(|a| {
                    a.firmware
                        .clear(&at.fault, &at.args)
                        .map_err(|source| RobotError::Fault {
                            joint: at.joint.clone(),
                            source,
                        })
                });
                let _ = reply.send(result);
            }
            Request::SetTemperature(joint, celsius, reply) => {
                let result = self.actuator_mut(&joint).and_then(|a| {
                    let celsius =
                        check_temperature_c(celsius).map_err(|source| RobotError::BadValue {
                            joint: joint.clone(),
                            source,
                        })?;
                    a.firmware.set_temperature(celsius);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::SetExternalTorque(joint, torque, reply) => {
                let result = self.actuator_mut(&joint).and_then(|a| {
                    let max = a.firmware.max_external_torque_nm();
                    let torque = within("torque_nm", torque, (-max, max)).map_err(|source| {
                        RobotError::BadValue {
                            joint: joint.clone(),
                            source,
                        }
                    })?;
                    a.firmware.set_external_torque(torque);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::SetBusLost(bus, lost, reply) => {
                let result = match self.ports.iter_mut().find(|p| p.name == bus) {
                    Some(port) => {
                        port.lost = lost;
                        Ok(())
                    }
                    None => Err(RobotError::UnknownBus { bus }),
                };
                let _ = reply.send(result);
            }
            Request::Snapshot(reply) => {
                let _ = reply.send(self.snapshot());
            }
            Request::ReleaseGantry(reply) => {
                let released = self.world.release_base();
                if released {
                    tracing::info!("robot: the gantry let go of the base");
                }
                let _ = reply.send(released);
            }
            Request::Shutdown(done) => {
                let _ = done.send(());
            }
        }
    }

    fn snapshot(&self) -> RobotSnapshot {
        let world = self.world.world();
        let q = world.joint_positions();
        let qd = world.joint_velocities();
        let base_position_m = base_pose(&self.world).position_m;
        let joints = self
            .actuators
            .iter()
            .enumerate()
            .map(|(k, a)| {
                let i = self.world.joint_index(k).unwrap_or(0);
                JointSnapshot {
                    joint: a.joint.clone(),
                    bus: self.ports[a.bus].name.clone(),
                    position_rad: q.get(i).copied().unwrap_or(0.0),
                    velocity_rad_s: qd.get(i).copied().unwrap_or(0.0),
                    actuator: a.firmware.snapshot(),
                }
            })
            .collect();
        RobotSnapshot {
            time_s: self.world.time_s(),
            base_position_m,
            base_rotation: base_rotation(&self.world),
            joints,
            lost_buses: self
                .ports
                .iter()
                .filter(|p| p.lost)
                .map(|p| p.name.clone())
                .collect(),
            gantry_holds: world.root_held(),
        }
    }

    async fn on_frame(
        &mut self,
        port: usize,
        received: &ReceivedFrame,
    ) -> Result<(), StateFileError> {
        let frame = &received.frame;
        if self.ports[port].lost {
            return Ok(());
        }
        let mut replies = Vec::new();
        let mut turnaround = Duration::ZERO;
        for a in self.actuators.iter_mut().filter(|a| a.bus == port) {
            // A classic controller does not take a CAN FD frame; replies in the frame's format.
            let answer = deliver(a.firmware.as_mut(), frame);
            if !answer.is_empty() {
                turnaround = turnaround.max(a.firmware.turnaround());
            }
            replies.extend(answer);
        }
        self.persist_if_requested()?;
        // Answered with the state of the latest step, after the slowest answering firmware's
        // turnaround (one batch per frame: a bus carries one reply at a time anyway), counted
        // from the request's last bit: the time this emulator took to get round to it is part
        // of the turnaround, not added to it.
        let delay = self.ports[port].bus.answer_delay(received, turnaround);
        self.send_after(port, replies, delay).await;
        Ok(())
    }

    async fn on_tick(&mut self) -> Result<(), PhysicsError> {
        let mut out: Vec<(usize, CanFrame)> = Vec::new();
        for a in &mut self.actuators {
            let bus = a.bus;
            out.extend(a.firmware.tick().into_iter().map(|f| (bus, f)));
        }
        let held = self.world.world().root_held();
        if held
            && self.gantry == Gantry::UntilEnabled
            && self.actuators.iter().all(|a| a.firmware.is_running())
        {
            self.world.release_base();
            tracing::info!("robot: every actuator is enabled; the gantry let go of the base");
        }
        self.world.step()?;
        *self.base.lock().unwrap_or_else(|e| e.into_inner()) = base_pose(&self.world);
        for port in 0..self.ports.len() {
            let frames = out
                .iter()
                .filter(|(bus, _)| *bus == port)
                .map(|(_, frame)| *frame);
            // Also a step without frames of its own sends what a busy bus refused earlier.
            self.send(port, frames).await;
        }
        Ok(())
    }

    fn persist_if_requested(&mut self) -> Result<(), StateFileError> {
        let mut changed = false;
        for a in &mut self.actuators {
            if a.firmware.take_persist_request() {
                let bus = &self.ports[a.bus].name;
                a.config.keep(bus, a.firmware.as_ref(), &mut self.state);
                changed = true;
            }
        }
        if let (true, Some(path)) = (changed, &self.state_path) {
            self.state.save(path)?;
        }
        Ok(())
    }

    async fn send(&mut self, port: usize, frames: impl IntoIterator<Item = CanFrame>) {
        self.send_after(port, frames, Duration::ZERO).await;
    }

    /// Hands `frames` to bus `port` to leave `delay` from now (a firmware's turnaround).
    async fn send_after(
        &mut self,
        port: usize,
        frames: impl IntoIterator<Item = CanFrame>,
        delay: Duration,
    ) {
        let port = &mut self.ports[port];
        if port.lost {
            return;
        }
        port.backlog
            .send_after(port.bus.as_ref(), frames, delay, "robot", &port.name)
            .await;
    }
}
