//! The emulator's "flash": what motors keep across an emulator restart (power cycle).
//!
//! JSON, keyed by the motor's UID (hex) so a motor keeps its state when its CAN ID changes,
//! after the header every emulator's state file carries (`"kind": "robstride"`, `"format"`,
//! see [`crate::state_file`]). Every value is checked on load with the rules of the commands
//! that store it ([`PersistedMotor::validate`]). Written atomically: a temporary file beside
//! the target, synced, then renamed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::robstride::firmware::{MotorConfig, PersistedMotor};
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
    /// A robot's actuators of other kinds, each kind's own JSON by its key
    /// (`damiao:can0:1`): a robot keeps every actuator's flash in one file.
    pub actuators: BTreeMap<String, serde_json::Value>,
}

/// The layout on disk: the header, then the motors.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    kind: String,
    format: u32,
    motors: BTreeMap<String, PersistedMotor>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    actuators: BTreeMap<String, serde_json::Value>,
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
            actuators: document.actuators,
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

    /// What this file keeps for `motor` (found by its UID), if anything.
    pub fn saved(&self, motor: &MotorConfig) -> Option<&PersistedMotor> {
        self.motors.get(&uid_key(motor.effective_uid()))
    }

    /// The CAN ID `motor` answers on at power-on: the one this file keeps for it (a host
    /// gave it one with "set CAN ID", comm type 7 or the MIT variant's command 7), else the
    /// configured one.
    pub fn power_on_id(&self, motor: &MotorConfig) -> u8 {
        self.saved(motor).map_or(motor.can_id, |saved| saved.can_id)
    }

    /// The first two of `motors` (each with how messages name it: `motor 1:RS03`, `joint
    /// `hip``), all on one bus, that this file (read from `path`) would put on one CAN ID at
    /// power-on. Two motors configured on one ID that the file leaves there are the
    /// configuration's mistake, not the file's, and not reported here (the caller refuses
    /// them): every clash found involves a motor the file moved.
    pub fn id_clash<'a>(
        &self,
        path: &Path,
        motors: impl IntoIterator<Item = (String, &'a MotorConfig)>,
    ) -> Option<IdClash> {
        let mut seen: Vec<ClashingMotor> = Vec::new();
        for (name, motor) in motors {
            let can_id = self.power_on_id(motor);
            let this = ClashingMotor {
                name,
                can_id,
                configured_id: motor.can_id,
                entry: format!("motors.{}", uid_key(motor.effective_uid())),
            };
            let clashes = |m: &&ClashingMotor| m.can_id == can_id && (m.moved() || this.moved());
            if let Some(first) = seen.iter().find(clashes) {
                return Some(IdClash {
                    can_id,
                    motors: [first.clone(), this],
                    state_file: path.to_owned(),
                });
            }
            seen.push(this);
        }
        None
    }

    /// Write so that the file is always complete (see [`state_file::save`]).
    pub fn save(&self, path: &Path) -> Result<(), StateFileError> {
        state_file::save(
            path,
            &Document {
                kind: STATE_FILE_KIND.to_owned(),
                format: state_file::FORMAT,
                motors: self.motors.clone(),
                actuators: self.actuators.clone(),
            },
        )
    }
}

/// Two motors on one bus that a state file would put on one CAN ID at power-on (a host moved
/// one onto the other's ID, or both onto a third, and the file kept it): they would answer
/// every frame for that ID together. The message names both, the ID, the file and how to
/// get out of it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IdClash {
    /// The ID both would answer on.
    pub can_id: u8,
    /// The two motors, in configuration order.
    pub motors: [ClashingMotor; 2],
    /// The state file.
    pub state_file: PathBuf,
}

/// One motor of an [`IdClash`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClashingMotor {
    /// How messages name it (`motor 1:RS03`, as the command line gives it).
    pub name: String,
    /// The ID the state file gives it (the clash's ID).
    pub can_id: u8,
    /// The ID it is configured with.
    pub configured_id: u8,
    /// Its entry in the state file (`motors.<uid>`; present for a motor the file moved).
    pub entry: String,
}

impl ClashingMotor {
    /// Whether the state file moved it off its configured ID.
    pub fn moved(&self) -> bool {
        self.can_id != self.configured_id
    }
}

impl std::fmt::Display for IdClash {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [first, second] = &self.motors;
        let moved: Vec<&ClashingMotor> = self.motors.iter().filter(|m| m.moved()).collect();
        let names: Vec<&str> = moved.iter().map(|m| m.name.as_str()).collect();
        let path = self.state_file.display();
        write!(
            f,
            "{} and {} would both answer on CAN ID {}: the state file {path} keeps {} there \
             (a host's \"set CAN ID\"). Two motors on one ID answer together and no host \
             could tell them apart again, so the emulator does not start. To fix it, edit \
             {path}: ",
            first.name,
            second.name,
            self.can_id,
            names.join(" and "),
        )?;
        for (k, m) in moved.iter().enumerate() {
            if k > 0 {
                write!(f, "; or ")?;
            }
            write!(
                f,
                "set `{}.can_id` to a free ID, or delete `{}` to put {} back on ID {} \
                 (its saved parameters and zero go with it)",
                m.entry, m.entry, m.name, m.configured_id
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for IdClash {}

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
    fn two_motors_moved_onto_one_id_clash_naming_both_and_each_entry() {
        let a = MotorConfig::new(1, crate::robstride::Model::RS03);
        let b = MotorConfig::new(2, crate::robstride::Model::RS02);
        let c = MotorConfig::new(3, crate::robstride::Model::RS00);
        let mut state = StateFile::default();
        for m in [&a, &c] {
            let moved = PersistedMotor {
                can_id: 7,
                ..motor()
            };
            state.motors.insert(uid_key(m.effective_uid()), moved);
        }
        let path = Path::new("dir/rs.json");
        let motors = [
            ("motor 1:RS03", &a),
            ("motor 2:RS02", &b),
            ("motor 3:RS00", &c),
        ];
        let clash = state
            .id_clash(path, motors.iter().map(|(n, m)| (n.to_string(), *m)))
            .expect("a clash");
        assert_eq!(clash.can_id, 7);
        assert_eq!(
            clash.motors.each_ref().map(|m| m.name.as_str()),
            ["motor 1:RS03", "motor 3:RS00"]
        );
        let text = clash.to_string();
        let entry = |m: &MotorConfig| format!("motors.{}", uid_key(m.effective_uid()));
        assert!(
            text.starts_with(
                "motor 1:RS03 and motor 3:RS00 would both answer on CAN ID 7: the state file \
                 dir/rs.json keeps motor 1:RS03 and motor 3:RS00 there"
            ),
            "{text}"
        );
        for m in [&a, &c] {
            assert!(
                text.contains(&format!("set `{}.can_id` to a free ID", entry(m))),
                "{text}"
            );
        }
        assert!(text.contains("put motor 3:RS00 back on ID 3"), "{text}");
        // Without the moved motor 3 there is no clash; the kept ID is what it powers on at.
        assert_eq!(
            state.id_clash(path, [("a".into(), &a), ("b".into(), &b)]),
            None
        );
        assert_eq!((state.power_on_id(&a), state.power_on_id(&b)), (7, 2));
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
