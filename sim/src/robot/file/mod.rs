//! Robot files: a whole robot as YAML — its URDF, a fixed or floating base, its buses and, per
//! actuated joint, the RobStride actuator driving it (grammar: `robots/README.md` in the
//! repository). [`load_robot_file`] reads one into a [`RobotConfig`](super::RobotConfig),
//! naming file, line and column for every problem ([`FileError`]).

mod error;
mod load;
mod raw;

pub use error::{FileError, Position};
pub use load::{load_robot_file, LoadedRobot, RobotFileError};
