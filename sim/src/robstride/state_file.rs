//! The emulator's "flash": what motors keep across an emulator restart (power cycle).
//!
//! JSON, keyed by the motor's UID (hex) so a motor keeps its state when its CAN ID changes,
//! after the header every emulator's state file carries (`"kind": "robstride"`, `"format"`,
//! see [`crate::state_file`]). Every value is checked on load with the rules of the commands
//! that store it ([`PersistedMotor::validate`]). Written atomically: a temporary file beside
//! the target, synced, then renamed.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::robstride::firmware::PersistedMotor;
use crate::state_file::{self, InvalidField};

/// Why the state file could not be read, checked or written (it names the file and field).
pub type StateFileError = state_file::StateFileError;

/// The value of `kind` in a RobStride state file.
pub const STATE_FILE_KIND: &str = "robstride";

/// The file's content.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateFile {
    /// Per-motor state by UID (16 hex digits).
    pub motors: BTreeMap<String, PersistedMotor>,
}

/// The layout on disk: the header, then the motors.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    kind: String,
    format: u32,
    motors: BTreeMap<String, PersistedMotor>,
}

/// UID as the file's key.
pub fn uid_key(uid: [u8; 8]) -> String {
    uid.iter().map(|byte| format!("{byte:02x}")).collect()
}

impl StateFile {
    /// Load; a missing file is an empty state (a motor's first power-on).
    pub fn load(path: &Path) -> Result<Self, StateFileError> {
        let Some(document) = state_file::load::<Document>(path, STATE_FILE_KIND)? else {
            return Ok(Self::default());
        };
        let file = Self {
            motors: document.motors,
        };
        file.validate()
            .map_err(|invalid| StateFileError::invalid(path, invalid))?;
        Ok(file)
    }

    /// Check every motor's key (a UID as [`uid_key`] writes it) and values.
    pub fn validate(&self) -> Result<(), InvalidField> {
        for (key, motor) in &self.motors {
            let prefix = format!("motors.{key}");
            let is_uid = key.len() == 16
                && key
                    .bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b));
            if !is_uid {
                return Err(InvalidField::new(
                    prefix,
                    "the key is not a UID (16 lower-case hex digits)",
                ));
            }
            motor.validate(&prefix)?;
        }
        Ok(())
    }

    /// Write so that the file is always complete (see [`state_file::save`]).
    pub fn save(&self, path: &Path) -> Result<(), StateFileError> {
        state_file::save(
            path,
            &Document {
                kind: STATE_FILE_KIND.to_owned(),
                format: state_file::FORMAT,
                motors: self.motors.clone(),
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn motor() -> PersistedMotor {
        PersistedMotor {
            can_id: 9,
            master_id: crate::robstride::DEFAULT_HOST_ID,
            zero_offset_rad: 0.25,
            params: BTreeMap::from([(0x7017, 3.5)]),
            baud_code: 1,
            protocol: 0,
        }
    }

    #[test]
    fn a_saved_state_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rs.json");
        let mut state = StateFile::default();
        state
            .motors
            .insert(uid_key([1, 2, 3, 4, 5, 6, 7, 8]), motor());
        state.save(&path).unwrap();
        assert_eq!(StateFile::load(&path).unwrap(), state);
    }

    #[test]
    fn values_no_command_would_store_are_refused_naming_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rs.json");
        let key = uid_key([1, 2, 3, 4, 5, 6, 7, 8]);
        for (field, bad) in [
            (
                "can_id",
                PersistedMotor {
                    can_id: 0,
                    ..motor()
                },
            ),
            (
                "can_id",
                PersistedMotor {
                    can_id: 200,
                    ..motor()
                },
            ),
            (
                "master_id",
                PersistedMotor {
                    master_id: 0,
                    ..motor()
                },
            ),
            (
                "baud_code",
                PersistedMotor {
                    baud_code: 9,
                    ..motor()
                },
            ),
            (
                "protocol",
                PersistedMotor {
                    protocol: 3,
                    ..motor()
                },
            ),
        ] {
            let mut state = StateFile::default();
            state.motors.insert(key.clone(), bad);
            state.save(&path).unwrap();
            let err = StateFile::load(&path).unwrap_err().to_string();
            assert!(
                err.contains("rs.json") && err.contains(&format!("motors.{key}.{field}")),
                "{field}: {err}"
            );
        }
        std::fs::write(&path, r#"{"kind":"piper","format":1,"flash":{}}"#).unwrap();
        let err = StateFile::load(&path).unwrap_err().to_string();
        assert!(err.contains("`kind`"), "{err}");
    }
}
