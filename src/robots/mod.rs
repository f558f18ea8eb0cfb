//! Robot files for the harness and the CLI: the emulator's reader
//! ([`sim::robot::file::load_robot_file`]) with its problems as [`ScenarioError`]s — the type
//! every file error of the harness has, its YAML reader's words rephrased as a scenario's are.

use std::path::{Path, PathBuf};

use sim::robot::file::{self, FileError};
use sim::robot::RobotConfig;

use crate::scenario::error::rephrase_yaml_message;
use crate::scenario::{Pos, ScenarioError};

/// A robot file that loaded.
#[derive(Debug, Clone)]
pub struct LoadedRobot {
    /// What the emulator runs.
    pub config: RobotConfig,
    /// The robot file.
    pub file: PathBuf,
    /// The URDF file it names.
    pub urdf_path: PathBuf,
    /// Choices that run but are probably wrong (an actuator weaker than its joint's URDF
    /// effort), each at its place in the file.
    pub warnings: Vec<ScenarioError>,
}

/// Why a robot file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum RobotFileError {
    /// The file could not be read (missing, not a regular file, too large).
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The file was read but is not a valid robot file.
    #[error("{0}")]
    Invalid(#[from] Box<ScenarioError>),
}

/// Loads and checks the robot file `path` and the URDF it names.
pub fn load_robot_file(path: &Path) -> Result<LoadedRobot, RobotFileError> {
    match file::load_robot_file(path) {
        Ok(loaded) => Ok(LoadedRobot {
            config: loaded.config,
            file: loaded.file,
            urdf_path: loaded.urdf_path,
            warnings: loaded.warnings.iter().map(scenario_error).collect(),
        }),
        Err(file::RobotFileError::Read { path, message }) => {
            Err(RobotFileError::Read { path, message })
        }
        Err(file::RobotFileError::Invalid(e)) => {
            Err(RobotFileError::Invalid(Box::new(scenario_error(&e))))
        }
    }
}

fn scenario_error(e: &FileError) -> ScenarioError {
    let message = if e.from_yaml_reader {
        rephrase_yaml_message(&e.message)
    } else {
        e.message.clone()
    };
    let mut error = ScenarioError::new(
        &e.file,
        Pos {
            line: e.at.line,
            column: e.at.column,
        },
        message,
    );
    error.source_line = e.source_line.clone();
    error
}

#[cfg(test)]
mod tests;
