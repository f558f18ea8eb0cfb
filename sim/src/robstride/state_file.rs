//! The emulator's "flash": what motors keep across an emulator restart (power cycle).
//!
//! JSON, keyed by the motor's UID (hex) so a motor keeps its state when its CAN ID changes.
//! Written atomically: a temporary file beside the target, then a rename.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::robstride::actuator::PersistedMotor;

/// Why the state file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum StateFileError {
    /// Reading or writing failed.
    #[error("state file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a state file of this format.
    #[error("state file {path}: line {line}, column {column}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What is wrong.
        message: String,
    },
}

/// The file's content.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StateFile {
    /// Format version (1).
    pub format: u32,
    /// Per-motor state by UID (16 hex digits).
    pub motors: BTreeMap<String, PersistedMotor>,
}

/// UID as the file's key.
pub fn uid_key(uid: [u8; 8]) -> String {
    uid.iter().map(|byte| format!("{byte:02x}")).collect()
}

impl StateFile {
    /// Load; a missing file is an empty state (a motor's first power-on).
    pub fn load(path: &Path) -> Result<Self, StateFileError> {
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(error) if error.kind() == std::io::ErrorKind::NotFound => {
                return Ok(Self {
                    format: 1,
                    motors: BTreeMap::new(),
                })
            }
            Err(source) => {
                return Err(StateFileError::Io {
                    path: path.to_owned(),
                    source,
                })
            }
        };
        serde_json::from_str(&text).map_err(|error| StateFileError::Format {
            path: path.to_owned(),
            line: error.line(),
            column: error.column(),
            message: error.to_string(),
        })
    }

    /// Write atomically (temporary file, flush to disk, rename over the target).
    pub fn save(&self, path: &Path) -> Result<(), StateFileError> {
        let io = |source| StateFileError::Io {
            path: path.to_owned(),
            source,
        };
        let text = serde_json::to_string_pretty(self).map_err(|error| StateFileError::Format {
            path: path.to_owned(),
            line: 0,
            column: 0,
            message: error.to_string(),
        })?;
        let mut temporary = path.as_os_str().to_owned();
        temporary.push(".tmp");
        let temporary = PathBuf::from(temporary);
        let mut file = std::fs::File::create(&temporary).map_err(io)?;
        file.write_all(text.as_bytes()).map_err(io)?;
        file.sync_all().map_err(io)?;
        drop(file);
        std::fs::rename(&temporary, path).map_err(io)
    }
}
