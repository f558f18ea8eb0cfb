//! RobStride actuator emulator: the private 29-bit CAN protocol (spec
//! `shared/protocols/robstride.md`), any number of motors on one bus, each driving a rig.
//!
//! - [`Actuator`]: one motor's firmware (pure: frames in, frames out, 1 ms ticks).
//! - [`model`]: per-model ranges and facts; [`params`]: the 0x70xx parameter table.
//! - [`rig`]: the load the motor drives and its URDF.
//! - [`RobstrideBus::spawn`]: many actuators on one [`bus::CanBus`], with a
//!   [`RobstrideHandle`] for the harness (faults, snapshots, shutdown).

mod actuator;
pub mod codec;
pub mod control;
pub mod faults;
pub mod model;
pub mod params;
pub mod rig;
mod runner;
pub mod state_file;

pub use actuator::{
    baud_code_bps, Actuator, ModeState, MotorConfig, MotorSnapshot, PersistedMotor, ReportType,
    DEFAULT_HOST_ID,
};
pub use faults::{Fault, Phase};
pub use model::{Model, ModelSpec, RangeTable, Ranges};
pub use rig::{Load, Plant, RigPlant};
pub use runner::{RobstrideBus, RobstrideConfig, RobstrideError, RobstrideHandle};
