//! The controller state machine: one arm on an [`ArmPlant`], stepped at 1 kHz, answering JSON
//! requests. Synchronous and transport-free: [`Controller::handle`] takes a parsed request
//! and returns the reply text (if the controller answers at all), [`Controller::tick`] advances
//! 1 ms, [`Controller::take_events`] hands out asynchronous messages (arrival events) with
//! the client each is addressed to.
//!
//! Power-on state (docs/protocols/realman.md §17): power on, every joint enabled with brakes
//! released, no error, default tool and work frames, push at cycle 1 to port 8089.

mod cmd_io;
mod cmd_ioports;
mod cmd_motion;
mod cmd_params;
mod cmd_periph;
mod cmd_state;
mod effectors;
mod motion;
pub mod peripherals;
mod status;
mod stream;
#[cfg(test)]
mod tests;

use std::collections::BTreeSet;
use std::path::PathBuf;

use serde_json::Value;

use super::facts::ModelFacts;
use super::faults::{codes, FaultError, RealmanFault, RealmanFaultKind};
use super::model::ArmModel;
use super::params::{self, Params, StateFileError};
use super::plant::{ArmPlant, PlantError};
use super::profile::FirmwareProfile;
use super::wire::Req;
use peripherals::Peripherals;

pub use effectors::{Gripper, Hand};
pub use motion::{Motion, TrajectoryType};
pub use status::ArmSnapshot;

/// One simulation step, s.
pub const STEP_S: f64 = 0.001;

/// Identifies a client connection (events are addressed to the client that asked for the move).
pub type ClientId = u64;

/// An asynchronous message for one client.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Event {
    /// The client to write it to.
    pub to: ClientId,
    /// Compact JSON text without terminator.
    pub text: String,
}

/// What the controller does with a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Answer {
    /// Write this reply (compact JSON, no terminator).
    Reply(String),
    /// A known command that is answered with silence (3rd-gen passthrough).
    Silent,
    /// Not a command this controller knows: no reply (logged by the caller).
    Unknown,
}

/// How to boot a controller.
#[derive(Debug, Clone)]
pub struct ControllerConfig {
    /// Arm model.
    pub model: ArmModel,
    /// Firmware release to impersonate.
    pub firmware: FirmwareProfile,
    /// Boot pose when no state file gives one, rad (default all zero).
    pub initial_joints_rad: Option<Vec<f64>>,
    /// Settings file written by `save_device_info_all` and read at boot.
    pub state_file: Option<PathBuf>,
    /// Whether a gripper is mounted on the flange.
    pub gripper: bool,
}

impl ControllerConfig {
    /// A controller for `model` with the default firmware and nothing else set.
    pub fn new(model: ArmModel) -> Self {
        Self {
            model,
            firmware: FirmwareProfile::default(),
            initial_joints_rad: None,
            state_file: None,
            gripper: true,
        }
    }
}

/// Why a controller could not boot.
#[derive(Debug, thiserror::Error)]
pub enum ControllerError {
    /// The state file is unreadable.
    #[error(transparent)]
    StateFile(#[from] StateFileError),
    /// The physics plant could not be built.
    #[error("cannot build the arm's physics: {0}")]
    Plant(#[from] PlantError),
    /// The boot pose has the wrong number of joints or non-finite values.
    #[error("boot pose needs {dof} finite joint angles")]
    BadInitialPose {
        /// Joints of the model.
        dof: usize,
    },
}

/// Errors the controller reports (`err[]`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Errors {
    /// Error of the last refused motion command (cleared by the next accepted one).
    pub planning: Option<u16>,
    /// Errors that stay until `clear_system_err` (and their cause is gone).
    pub latched: BTreeSet<u16>,
}

impl Errors {
    /// Every active code, ascending.
    pub fn codes(&self) -> Vec<u16> {
        let mut all: BTreeSet<u16> = self.latched.clone();
        all.extend(self.planning);
        all.into_iter().collect()
    }
}

/// The controller.
pub struct Controller {
    model: ArmModel,
    facts: ModelFacts,
    profile: FirmwareProfile,
    params: Params,
    state_file: Option<PathBuf>,
    plant: ArmPlant,
    setpoint_rad: Vec<f64>,
    prev_setpoint_rad: Vec<f64>,
    power_on: bool,
    enabled: Vec<bool>,
    joint_err: Vec<u16>,
    errors: Errors,
    estop: bool,
    motion: Motion,
    gripper: Option<Gripper>,
    hand: Hand,
    peripherals: Peripherals,
    time_ms: u64,
    events: Vec<Event>,
}

impl std::fmt::Debug for Controller {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Controller")
            .field("product", &self.facts.product)
            .field("firmware", &self.profile)
            .field("time_ms", &self.time_ms)
            .finish()
    }
}

impl Controller {
    /// Boot: settings from the state file if there is one, else factory settings.
    pub fn new(config: ControllerConfig) -> Result<Self, ControllerError> {
        let facts = ModelFacts::of(&config.model);
        let dof = facts.dof;
        let stored = match &config.state_file {
            Some(path) => params::load(path, dof)?,
            None => None,
        };
        let params = stored.unwrap_or_else(|| Params::factory(&facts));
        let boot_rad = match (&params.joints_deg, &config.initial_joints_rad) {
            (Some(deg), _) => deg.iter().map(|d| d.to_radians()).collect(),
            (None, Some(rad)) => rad.clone(),
            (None, None) => vec![0.0; dof],
        };
        if boot_rad.len() != dof || boot_rad.iter().any(|v| !v.is_finite()) {
            return Err(ControllerError::BadInitialPose { dof });
        }
        let plant = ArmPlant::new(&config.model, &boot_rad)?;
        Ok(Self {
            model: config.model,
            profile: config.firmware,
            params,
            state_file: config.state_file,
            plant,
            setpoint_rad: boot_rad.clone(),
            prev_setpoint_rad: boot_rad,
            power_on: true,
            enabled: vec![true; dof],
            joint_err: vec![0; dof],
            errors: Errors::default(),
            estop: false,
            motion: Motion::default(),
            gripper: config.gripper.then(Gripper::default),
            hand: Hand::default(),
            peripherals: Peripherals::default(),
            time_ms: 0,
            events: Vec::new(),
            facts,
        })
    }

    /// Model facts (product name, joints, default limits).
    pub fn facts(&self) -> &ModelFacts {
        &self.facts
    }

    /// Current settings.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Firmware profile.
    pub fn firmware(&self) -> FirmwareProfile {
        self.profile
    }

    /// Milliseconds since boot.
    pub fn time_ms(&self) -> u64 {
        self.time_ms
    }

    /// Answer one request from `client`.
    pub fn handle(&mut self, client: ClientId, request: &Value) -> Answer {
        let req = Req(request);
        let Some(name) = req.command() else {
            return Answer::Unknown;
        };
        let answer = cmd_motion::handle(self, client, name, req)
            .or_else(|| cmd_state::handle(self, name, req))
            .or_else(|| cmd_params::handle(self, name, req))
            .or_else(|| cmd_io::handle(self, client, name, req))
            .or_else(|| cmd_ioports::handle(self, name, req))
            .or_else(|| cmd_periph::handle(self, name, req));
        answer.unwrap_or(Answer::Unknown)
    }

    /// Forget a client: its events are no longer produced (its motions still run).
    pub fn disconnect(&mut self, client: ClientId) {
        self.motion.forget_client(client);
        self.events.retain(|e| e.to != client);
    }

    /// Advance 1 ms: motion, effectors, physics.
    pub fn tick(&mut self) {
        self.time_ms += 1;
        if self.can_hold() {
            self.tick_motion();
        } else {
            self.hold_where_stopped();
        }
        self.tick_effectors();
        let speeds: Vec<f64> = self
            .setpoint_rad
            .iter()
            .zip(&self.prev_setpoint_rad)
            .map(|(a, b)| (a - b) / STEP_S)
            .collect();
        self.plant.set_target(&self.setpoint_rad, &speeds);
        self.plant.step();
        self.prev_setpoint_rad.clone_from(&self.setpoint_rad);
    }

    /// The set-point while the arm cannot follow a motion (a joint disabled, power off,
    /// emergency stop). A braked joint's set-point follows the arm, so that re-enabling it
    /// never jumps. A joint still under servo keeps the set-point it had when the motion
    /// stopped: it holds that position. Following the arm there too would make the reference
    /// the arm's own state — no stiffness, and the speed feed-forward (the set-point's
    /// change) would echo the arm's own motion, so a joint that was moving would keep going.
    fn hold_where_stopped(&mut self) {
        let measured = self.plant.positions_rad();
        for (j, (setpoint, q)) in self.setpoint_rad.iter_mut().zip(measured).enumerate() {
            if self.plant.is_braked(j) {
                *setpoint = q;
            }
        }
    }

    /// Messages produced since the last call (arrival events), oldest first.
    pub fn take_events(&mut self) -> Vec<Event> {
        std::mem::take(&mut self.events)
    }

    /// Whether the joints hold position under power (they can follow a set-point).
    fn can_hold(&self) -> bool {
        self.power_on && !self.estop && self.enabled.iter().all(|e| *e)
    }

    /// Whether a new motion command may be accepted.
    fn can_move(&self) -> bool {
        self.can_hold() && self.errors.latched.is_empty() && self.joint_err.iter().all(|e| *e == 0)
    }

    /// Apply a controller-side fault.
    pub fn inject(&mut self, fault: &RealmanFault) -> Result<(), FaultError> {
        match *fault {
            RealmanFault::JointError { joint, code } => {
                let j = self.joint_index(joint)?;
                if code == 0 {
                    return Err(FaultError::ZeroCode);
                }
                self.joint_err[j] |= code;
                self.enabled[j] = false;
                self.plant.set_enabled(j, false);
                self.errors.latched.insert(codes::JOINT_COMM);
                self.abort_motion();
            }
            RealmanFault::PowerLoss => self.set_power(false),
            RealmanFault::Collision => {
                self.errors.latched.insert(codes::COLLISION);
                self.abort_motion();
            }
            RealmanFault::EStop => {
                self.estop = true;
                self.errors.latched.insert(codes::JOINT_DISABLED);
                self.plant.set_brakes(true);
                self.abort_motion();
            }
            RealmanFault::GripperFault { bits } => {
                if let Some(g) = &mut self.gripper {
                    g.error_bits |= bits.max(1);
                }
                self.errors.latched.insert(codes::GRIPPER);
            }
            // Transport faults are applied by the server.
            _ => {}
        }
        Ok(())
    }

    /// Remove a controller-side fault's cause (the reported error still needs
    /// `clear_system_err` where the real controller needs it).
    pub fn clear(&mut self, kind: RealmanFaultKind) {
        match kind {
            RealmanFaultKind::JointError => {
                self.joint_err.iter_mut().for_each(|e| *e = 0);
                self.errors.latched.remove(&codes::JOINT_COMM);
                for j in 0..self.enabled.len() {
                    self.enabled[j] = true;
                    self.plant.set_enabled(j, true);
                }
            }
            RealmanFaultKind::PowerLoss => self.set_power(true),
            RealmanFaultKind::Collision => {
                self.errors.latched.remove(&codes::COLLISION);
            }
            RealmanFaultKind::EStop => {
                self.estop = false;
                self.plant.set_brakes(!self.power_on);
            }
            RealmanFaultKind::GripperFault => {
                if let Some(g) = &mut self.gripper {
                    g.error_bits = 0;
                }
                self.errors.latched.remove(&codes::GRIPPER);
            }
            _ => {}
        }
    }

    fn joint_index(&self, joint: u8) -> Result<usize, FaultError> {
        let dof = self.facts.dof;
        if joint == 0 || usize::from(joint) > dof {
            return Err(FaultError::NoSuchJoint { joint, dof });
        }
        Ok(usize::from(joint) - 1)
    }

    fn set_power(&mut self, on: bool) {
        if !on {
            self.abort_motion();
        }
        self.power_on = on;
        self.plant.set_brakes(!on || self.estop);
        for j in 0..self.enabled.len() {
            self.enabled[j] = on;
            self.plant.set_enabled(j, on);
        }
    }

    /// Write the settings (and the current pose) to the state file, if one is configured.
    pub(crate) fn save_state(&mut self) -> Result<(), StateFileError> {
        self.params.joints_deg = Some(
            self.plant
                .positions_rad()
                .iter()
                .map(|r| r.to_degrees())
                .collect(),
        );
        match &self.state_file {
            Some(path) => params::save(path, &self.params),
            None => Ok(()),
        }
    }
}
