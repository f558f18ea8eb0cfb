//! The actuator contract: what a robot joint's actuator offers the robot that carries it,
//! whatever its kind. A robot's runner drives every joint through [`ActuatorFirmware`] and
//! each firmware drives its joint through a [`ShaftPlant`]; the robot file's `model:` is
//! resolved by [`registry`] among the kinds that declare themselves actuators.
//!
//! - [`ShaftPlant`]: the single shaft an actuator turns (a rig, or a joint of a robot's world).
//! - [`ActuatorFirmware`]: one actuator's firmware, frames in and frames out, ticked every
//!   millisecond; its state as an [`ActuatorSnapshot`]; its faults by name, from its table.
//! - [`registry`]: the actuator kinds and the model names each answers to (each kind's entry
//!   in its own folder, `sim/src/<kind>/actuator.rs`), and [`ActuatorConfig`], one actuator's
//!   settings of any kind.
//! - `bus_runner`: actuators of one kind on one bus, one task serving them (what
//!   `RobstrideBus` and `DamiaoBus` run on).

pub(crate) mod bus_runner;
pub mod registry;
mod snapshot;

use std::time::Duration;

use bus::CanFrame;

use crate::fault_args::{FaultArgError, FaultArgs};
use crate::fault_desk::FaultInfo;

pub use registry::{
    configure, ActuatorConfig, ActuatorKind, ActuatorModel, ActuatorSetup, AnySetup,
    ConfigureError, PowerOn, KINDS,
};
pub use snapshot::{ActuatorSnapshot, Detail};

/// `replies` in the format of `request`: CAN FD frames with its flags when it was one (a
/// firmware answers in the format it was addressed in), as they are otherwise.
pub fn in_format_of(request: &CanFrame, replies: Vec<CanFrame>) -> Vec<CanFrame> {
    let Some(flags) = request.fd_flags() else {
        return replies;
    };
    // A classic payload (0..=8 bytes) is a valid FD length: the conversion cannot fail.
    replies
        .into_iter()
        .map(|reply| CanFrame::fd(reply.id(), reply.data(), flags).unwrap_or(reply))
        .collect()
}

/// `frame` handed to `firmware` as its CAN controller takes it: a CAN FD frame only if it
/// [`speaks_fd`](ActuatorFirmware::speaks_fd) (a classic controller never sees one, as on
/// hardware), and its replies in the frame's format ([`in_format_of`]). What every runner
/// does with a frame from the bus.
pub fn deliver<F: ActuatorFirmware + ?Sized>(firmware: &mut F, frame: &CanFrame) -> Vec<CanFrame> {
    if frame.is_fd() && !firmware.speaks_fd() {
        return Vec::new();
    }
    in_format_of(frame, firmware.handle_frame(frame))
}

/// A single shaft an actuator drives: a rig on a bench, or one joint of a robot's world.
pub trait ShaftPlant: Send + Sync {
    /// Advance by `dt_s` with the motor applying `torque_nm`.
    fn step(&mut self, torque_nm: f64, dt_s: f64);
    /// Shaft angle (rad), not wrapped.
    fn position_rad(&self) -> f64;
    /// Shaft speed (rad/s).
    fn velocity_rad_s(&self) -> f64;
    /// Total inertia seen by the motor (kg·m²).
    fn inertia_kg_m2(&self) -> f64;
    /// An external torque on the shaft (N·m), e.g. a hand pushing the load.
    fn set_external_torque_nm(&mut self, torque_nm: f64);
}

/// One actuator's firmware as a robot runs it: pure (frames in, frames out, one tick per
/// millisecond of emulated time), whatever the kind. Side doors (temperature, a push, faults)
/// are what a test bench does to the motor from outside.
pub trait ActuatorFirmware: Send {
    /// The kind's name (`robstride`, `damiao`), as the registry lists it.
    fn kind(&self) -> &'static str;
    /// The CAN identifier the actuator is addressed by now (a host may have moved it).
    fn can_id(&self) -> u32;
    /// Answers one frame from the bus (most frames get one reply; frames for others none).
    /// A CAN FD frame reaches only a firmware that [`speaks_fd`](Self::speaks_fd); its replies
    /// then leave as CAN FD frames with the request's flags (the runners do both, through
    /// [`deliver`]).
    fn handle_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame>;
    /// Whether its CAN controller takes CAN FD frames (and answers in the format it was
    /// addressed in). A classic controller never sees them, as on hardware: false unless the
    /// kind says.
    fn speaks_fd(&self) -> bool {
        false
    }
    /// Runs one millisecond: control loops, plant substeps, periodic frames it sends.
    fn tick(&mut self) -> Vec<CanFrame>;
    /// Whether the actuator is enabled (its loops drive the joint).
    fn is_running(&self) -> bool;
    /// Whether the actuator would send nothing unasked for now (no periodic report, no
    /// watchdog about to fire): a robot whose actuators all say so may let its clock rest.
    fn sends_nothing_on_its_own(&self) -> bool;
    /// How long after a command's last bit the reply's first bit leaves (firmware turnaround).
    fn turnaround(&self) -> Duration;
    /// Plant substeps per tick (a robot's world steps once per tick for all joints: 1).
    fn set_control_substeps(&mut self, substeps: u32);
    /// Its state, in the words every front end shows.
    fn snapshot(&self) -> ActuatorSnapshot;
    /// Set the winding temperature (°C); the value is already range-checked.
    fn set_temperature(&mut self, celsius: f64);
    /// Push the shaft with an external torque (N·m) until changed; already range-checked.
    fn set_external_torque(&mut self, torque_nm: f64);
    /// Largest external push the side door takes (N·m): a few times the peak torque.
    fn max_external_torque_nm(&self) -> f64;
    /// The faults this kind can have injected, with their parameters.
    fn fault_table(&self) -> Vec<FaultInfo>;
    /// Inject the fault `name` with `args` (checked against [`Self::fault_table`]); frames the
    /// firmware sends at once (a fault report) are returned.
    fn inject(&mut self, name: &str, args: &FaultArgs) -> Result<Vec<CanFrame>, FaultArgError>;
    /// Remove the cause of fault `name`; a latched fault stays until the host clears it.
    fn clear(&mut self, name: &str, args: &FaultArgs) -> Result<(), FaultArgError>;
    /// Whether a host asked to save the actuator's settings since the last call (its
    /// flash); the robot then writes [`Self::persisted`] to its state file.
    fn take_persist_request(&mut self) -> bool;
    /// What the actuator keeps across power cycles, as its kind's state file stores it.
    fn persisted(&self) -> serde_json::Value;
}
