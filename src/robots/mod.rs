//! Robot files: a whole robot for `armhil sim robot` — its URDF, a fixed or floating base,
//! its buses and, per actuated joint, the RobStride actuator driving it (grammar:
//! `robots/README.md`). [`load_robot_file`] reads one into the emulator's
//! [`sim::robot::RobotConfig`], naming file, line and column for every problem.

mod load;
mod raw;

pub use load::{load_robot_file, LoadedRobot, RobotFileError};

#[cfg(test)]
mod tests;
