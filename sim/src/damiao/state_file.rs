//! The "flash" of a Damiao bus served alone (`armhil sim damiao --state-file`): each motor's
//! flash image (what [`crate::actuator::ActuatorFirmware::persisted`] writes: the read-write
//! registers of its last save and the zero of its last `FE`), keyed by the ESC_ID the motor is
//! configured with, after the header every emulator's state file carries (`"kind": "damiao"`,
//! `"format"`, see [`crate::state_file`]). A robot keeps its Damiao motors' images in its own
//! state file instead.
//!
//! Damiao motors have no UID: the configured ESC_ID names a motor across runs, as the
//! configured CAN ID does in a robot's file. A motor a host moved (a write of ESC_ID, then a
//! save) powers on at the ESC_ID its image holds. Every image is checked on load with the
//! rules the register writes apply ([`crate::damiao::PersistedMotor::validate`]).

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::damiao::firmware::{MotorConfig, MAX_ID};
use crate::state_file::{self, InvalidField, StateFileError};

/// The value of `kind` in a Damiao state file.
pub const STATE_FILE_KIND: &str = "damiao";

/// The file's content.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateFile {
    /// Each motor's flash image by its configured ESC_ID ([`motor_key`]).
    pub motors: BTreeMap<String, serde_json::Value>,
}

/// The layout on disk: the header, then the motors.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    kind: String,
    format: u32,
    motors: BTreeMap<String, serde_json::Value>,
}

/// A motor's key in the file: its configured ESC_ID in decimal (`"1"`), as the command line
/// and a robot's file write it.
pub fn motor_key(esc_id: u16) -> String {
    esc_id.to_string()
}

impl StateFile {
    /// Load; a missing file is an empty state (the motors' first power-on). Every key must be
    /// an ESC_ID as [`motor_key`] writes it; the images are checked when a motor powers on
    /// with one ([`StateFile::power_on`]), against its model.
    pub fn load(path: &Path) -> Result<Self, StateFileError> {
        let Some(document) = state_file::load::<Document>(path, STATE_FILE_KIND)? else {
            return Ok(Self::default());
        };
        for key in document.motors.keys() {
            let is_id = key
                .parse::<u16>()
                .is_ok_and(|id| id <= MAX_ID && motor_key(id) == *key);
            if !is_id {
                return Err(StateFileError::invalid(
                    path,
                    InvalidField::new(
                        format!("motors.{key}"),
                        "the key is not an ESC_ID (a whole number 0..=2047, no leading zeros)",
                    ),
                ));
            }
        }
        Ok(Self {
            motors: document.motors,
        })
    }

    /// Whether the file keeps an image for the motor configured on `esc_id`.
    pub fn keeps(&self, esc_id: u16) -> bool {
        self.motors.contains_key(&motor_key(esc_id))
    }

    /// What `motor` powers on with: the image this file keeps for it applied (its ESC_ID and
    /// MST_ID are the image's, its serial number stays the configured motor's), or `motor`
    /// itself when the file keeps none. An image the motor's firmware would refuse is an
    /// error naming its field (`motors.1.registers.CTRL_MODE`).
    pub fn power_on(&self, motor: &MotorConfig) -> Result<MotorConfig, InvalidField> {
        let key = motor_key(motor.esc_id);
        let Some(image) = self.motors.get(&key) else {
            return Ok(motor.clone());
        };
        let kept = MotorConfig::from_persisted(motor.model, image).map_err(|e| {
            let field = match e.field.strip_prefix("flash") {
                Some(rest) => format!("motors.{key}{rest}"),
                None => format!("motors.{key}.{}", e.field),
            };
            InvalidField::new(field, e.problem)
        })?;
        Ok(MotorConfig {
            esc_id: kept.esc_id,
            mst_id: kept.mst_id,
            flash: kept.flash,
            serial_number: Some(motor.effective_serial()),
            ..motor.clone()
        })
    }

    /// Keep `image` for the motor configured on `esc_id`.
    pub fn keep(&mut self, esc_id: u16, image: serde_json::Value) {
        self.motors.insert(motor_key(esc_id), image);
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
    use crate::damiao::Model;

    fn image(esc_id: u16, mst_id: u16) -> serde_json::Value {
        serde_json::json!({
            "registers": {"ESC_ID": esc_id, "MST_ID": mst_id, "TIMEOUT": 200.0},
            "zero_offset_rad": 0.5
        })
    }

    #[test]
    fn a_kept_image_moves_the_motor_and_keeps_its_serial_and_load() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("dm.json");
        let mut state = StateFile::default();
        state.keep(1, image(5, 0x25));
        state.save(&path).unwrap();
        let state = StateFile::load(&path).unwrap();
        let configured = MotorConfig::new(1, Model::DM4340);
        let powered = state.power_on(&configured).unwrap();
        assert_eq!((powered.esc_id, powered.mst_id), (5, 0x25));
        assert_eq!(powered.serial_number, Some(configured.effective_serial()));
        assert_eq!(powered.load, configured.load);
        assert!(powered.flash.is_some());
        // A motor the file keeps nothing for powers on as configured.
        let other = MotorConfig::new(2, Model::DM4310);
        assert_eq!(state.power_on(&other).unwrap(), other);
        assert!(state.keeps(1) && !state.keeps(2));
    }

    #[test]
    fn a_bad_key_or_image_is_refused_naming_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("dm.json");
        std::fs::write(
            &path,
            r#"{"kind": "damiao", "format": 1, "motors": {"01": {}}}"#,
        )
        .unwrap();
        let err = StateFile::load(&path).unwrap_err().to_string();
        assert!(err.contains("`motors.01`"), "{err}");
        std::fs::write(&path, r#"{"kind": "robstride", "format": 1, "motors": {}}"#).unwrap();
        assert!(StateFile::load(&path).is_err());

        let mut state = StateFile::default();
        state.keep(
            1,
            serde_json::json!({"registers": {"ESC_ID": 1.0, "CTRL_MODE": 9.0}, "zero_offset_rad": 0.0}),
        );
        let err = state
            .power_on(&MotorConfig::new(1, Model::DM4310))
            .unwrap_err();
        assert_eq!(err.field, "motors.1.registers.CTRL_MODE");
        state.keep(1, serde_json::json!({"zero": 1}));
        let err = state
            .power_on(&MotorConfig::new(1, Model::DM4310))
            .unwrap_err();
        assert_eq!(err.field, "motors.1");
    }
}
