//! Whole robots: one URDF in one physics world, each actuated joint driven by an emulated
//! RobStride actuator, each actuator answering on its own bus.
//!
//! - [`RobotConfig`]: the URDF, a fixed or floating [`Base`], the buses, and per actuated
//!   joint the motor, bus, direction and zero offset; [`file::load_robot_file`] reads a
//!   robot file (YAML) into it.
//! - [`RobotWorld`]: the physics; how the actuators' 10 kHz control loops meet a 1 kHz world
//!   step is explained in [`joint_plant`].
//! - [`RobotEmulator::spawn`]: every bus served at once by one task (1 ms steps on absolute
//!   deadlines in real time, or under a paused clock), with a [`RobotHandle`] for faults per
//!   joint and per bus, snapshots and shutdown. A state file keeps every actuator's flash.
//! - [`faults`]: the one builder of a robot's faults for the web view and Python.

mod base_pose;
mod config;
pub mod faults;
pub mod file;
pub mod joint_plant;
mod runner;
mod world;

pub use base_pose::BasePose;
pub use config::{Base, BusConfig, Gantry, JointActuator, RobotConfig, RobotConfigError};
pub use faults::{RobotFault, RobotLayout};
pub use runner::{
    check_kept_ids, JointSnapshot, RobotEmulator, RobotError, RobotHandle, RobotMonitor,
    RobotSnapshot,
};
pub use world::{RobotWorld, RobotWorldError};
