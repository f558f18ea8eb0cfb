//! Robot files for the harness and the CLI: the emulator's reader, whose messages are worded
//! as a scenario's are ([`sim::yaml_words`]).

pub use sim::robot::file::{load_robot_file, FileError, LoadedRobot, RobotFileError};

#[cfg(test)]
mod tests;
