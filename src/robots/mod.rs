//! Robot files for the harness and the CLI: the emulator's reader
//! ([`sim::robot::file::load_robot_file`]) with its YAML reader's words rephrased as a
//! scenario's are ("unknown key `x`; did you mean `y`?").

use std::path::Path;

pub use sim::robot::file::{FileError, LoadedRobot, RobotFileError};

use crate::scenario::error::rephrase_yaml_message;

/// Loads and checks the robot file `path` and the URDF it names.
pub fn load_robot_file(path: &Path) -> Result<LoadedRobot, RobotFileError> {
    sim::robot::file::load_robot_file(path).map_err(|error| match error {
        RobotFileError::Invalid(mut e) if e.from_yaml_reader => {
            e.message = rephrase_yaml_message(&e.message);
            e.from_yaml_reader = false;
            RobotFileError::Invalid(e)
        }
        other => other,
    })
}

#[cfg(test)]
mod tests;
