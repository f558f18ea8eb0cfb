//! The master controller's non-volatile parameters ("flash"), optionally persisted to a JSON
//! state file so they survive emulator restarts.

use std::ops::RangeInclusive;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::state_file::{self, InvalidField};

/// Default max angle per joint, 0.1° (the real 0x473 replies of spec §6.4 (OBS)).
pub const DEFAULT_MAX_ANGLE_DDEG: [i16; 6] = [1500, 1800, 0, 890, 890, 1800];
/// Default min angle per joint, 0.1°.
pub const DEFAULT_MIN_ANGLE_DDEG: [i16; 6] = [-1500, 0, -1700, -890, -890, -1800];
/// Default max joint speed, 0.01 rad/s (3.0 rad/s, spec §9.2).
pub const DEFAULT_MAX_SPEED_CRAD_S: u16 = 300;
/// Default max joint acceleration, 0.01 rad/s² (5.0 rad/s², spec §6.4b).
pub const DEFAULT_MAX_ACC_CRAD_S2: u16 = 500;
/// Hardware ceiling of the joint speed, 0.01 rad/s: larger settings are clamped to it.
pub const MAX_SPEED_CEILING_CRAD_S: u16 = 300;
/// Hardware ceiling of the joint acceleration, 0.01 rad/s² (SDK accepts 0–5 rad/s²).
pub const MAX_ACC_CEILING_CRAD_S2: u16 = 500;
/// Default end-effector limits: 1.0 m/s, 1.0 rad/s, 1.0 m/s², 1.0 rad/s² (spec §6.9 capture).
pub const DEFAULT_END_VEL_ACC: [u16; 4] = [1000, 1000, 1000, 1000];

/// Leader/follower role stored in flash (0x470).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum LinkageRole {
    /// Motion-output arm (default).
    #[default]
    Follower,
    /// Teach-input arm: takes effect after a restart or a return to standby.
    Leader,
}

/// Every persisted parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Flash {
    /// Max joint angle, 0.1°.
    pub max_angle_ddeg: [i16; 6],
    /// Min joint angle, 0.1°.
    pub min_angle_ddeg: [i16; 6],
    /// Max joint speed, 0.01 rad/s.
    pub max_speed_crad_s: [u16; 6],
    /// Max joint acceleration, 0.01 rad/s².
    pub max_acc_crad_s2: [u16; 6],
    /// Encoder zero offsets set by 0x475 (reported angle = physical − offset), rad.
    pub zero_offset_rad: [f64; 6],
    /// End-effector limits (mm/s, mrad/s, mm/s², mrad/s²).
    pub end_vel_acc: [u16; 4],
    /// Collision protection level per joint, 0–8 (0 = off).
    pub collision_levels: [u8; 6],
    /// Teach-pendant travel coefficient, %.
    pub pendant_travel_pct: u8,
    /// Max gripper stroke, mm (0 = never set: the gripper reports 0 and ignores commands).
    pub gripper_max_stroke_mm: u8,
    /// Teach-pendant friction 1–10.
    pub pendant_friction: u8,
    /// Gripper zero offset set by 0x159 byte 7 = 0xAE, m of stroke.
    pub gripper_zero_offset_m: f64,
    /// Whether the gripper has ever been zeroed (0x2A8 status bit 7).
    pub gripper_homed: bool,
    /// Leader/follower role.
    pub linkage_role: LinkageRole,
    /// Feedback ID offset (0, 0x10, 0x20).
    pub feedback_offset: u8,
    /// Control ID offset (0, 0x10, 0x20).
    pub control_offset: u8,
    /// Offset a leader emits on (0, 0x10, 0x20).
    pub target_offset: u8,
    /// Installation position 1–3.
    pub install_position: u8,
    /// End payload 0 empty, 1 half, 2 full.
    pub payload: u8,
    /// Joint assistance levels (0x487).
    pub assist_levels: [u8; 6],
}

impl Default for Flash {
    fn default() -> Self {
        Self {
            max_angle_ddeg: DEFAULT_MAX_ANGLE_DDEG,
            min_angle_ddeg: DEFAULT_MIN_ANGLE_DDEG,
            max_speed_crad_s: [DEFAULT_MAX_SPEED_CRAD_S; 6],
            max_acc_crad_s2: [DEFAULT_MAX_ACC_CRAD_S2; 6],
            zero_offset_rad: [0.0; 6],
            end_vel_acc: DEFAULT_END_VEL_ACC,
            collision_levels: [0; 6],
            pendant_travel_pct: 100,
            gripper_max_stroke_mm: 70,
            pendant_friction: 1,
            gripper_zero_offset_m: 0.0,
            gripper_homed: false,
            linkage_role: LinkageRole::Follower,
            feedback_offset: 0,
            control_offset: 0,
            target_offset: 0,
            install_position: 1,
            payload: 0,
            assist_levels: [0; 6],
        }
    }
}

/// Reading, checking or writing the state file failed (it names the file and the field).
pub type FlashError = crate::state_file::StateFileError;

/// The value of `kind` in a Piper state file.
pub const STATE_FILE_KIND: &str = "piper";

/// What the firmware's set commands accept, shared by the commands and by the state-file check
/// so that the two can never disagree (a file can only hold what a command could have stored).
pub mod rules {
    use std::ops::RangeInclusive;

    /// Collision protection levels of 0x47A (0 = off).
    pub const COLLISION_LEVELS: RangeInclusive<u8> = 0..=8;
    /// Teach-pendant travel coefficient of 0x47D, %.
    pub const PENDANT_TRAVEL_PCT: RangeInclusive<u8> = 100..=200;
    /// Max gripper stroke of 0x47D, mm.
    pub const GRIPPER_MAX_STROKE_MM: RangeInclusive<u8> = 0..=200;
    /// Teach-pendant friction of 0x47D.
    pub const PENDANT_FRICTION: RangeInclusive<u8> = 1..=10;
    /// Installation positions of 0x151 byte 5 that are stored (0 = unchanged).
    pub const INSTALL_POSITIONS: RangeInclusive<u8> = 1..=3;
    /// End payloads of 0x477 byte 4 (empty, half, full).
    pub const PAYLOADS: RangeInclusive<u8> = 0..=2;

    /// Whether `offset` is a CAN ID offset 0x470 accepts (0x00, 0x10, 0x20).
    pub fn is_id_offset(offset: u8) -> bool {
        matches!(offset, 0x00 | 0x10 | 0x20)
    }

    /// Why a joint's min/max angle pair (0.1°) is refused by 0x474, if it is.
    pub fn joint_limits(min_ddeg: i16, max_ddeg: i16) -> Result<(), String> {
        if min_ddeg > max_ddeg {
            Err(format!(
                "min angle {min_ddeg} (0.1°) is above max angle {max_ddeg}"
            ))
        } else {
            Ok(())
        }
    }
}

impl Flash {
    /// Min/max limits of a joint in radians (reported frame).
    pub fn limits_rad(&self, joint: usize) -> (f64, f64) {
        (
            (f64::from(self.min_angle_ddeg[joint]) / 10.0).to_radians(),
            (f64::from(self.max_angle_ddeg[joint]) / 10.0).to_radians(),
        )
    }

    /// Max joint speed in rad/s.
    pub fn max_speed_rad_s(&self, joint: usize) -> f64 {
        f64::from(self.max_speed_crad_s[joint]) / 100.0
    }

    /// Max joint acceleration in rad/s².
    pub fn max_acc_rad_s2(&self, joint: usize) -> f64 {
        f64::from(self.max_acc_crad_s2[joint]) / 100.0
    }

    /// Restore joint limits, speeds and accelerations (0x477 byte 1 = 2).
    pub fn reset_joint_params(&mut self) {
        let d = Self::default();
        self.max_angle_ddeg = d.max_angle_ddeg;
        self.min_angle_ddeg = d.min_angle_ddeg;
        self.max_speed_crad_s = d.max_speed_crad_s;
        self.max_acc_crad_s2 = d.max_acc_crad_s2;
    }

    /// Check every value against what the set commands would have stored ([`rules`]; speeds
    /// and accelerations are clamped to their ceilings by the commands, so a larger stored
    /// value is refused). Zero offsets depend on the URDF and are checked at boot. Fields are
    /// named as in the state file (`flash.min_angle_ddeg[2]`).
    pub fn validate(&self) -> Result<(), InvalidField> {
        let field = |name: &str, i: Option<usize>| match i {
            Some(i) => format!("flash.{name}[{i}]"),
            None => format!("flash.{name}"),
        };
        let in_range = |name: &str, i: Option<usize>, v: u8, range: RangeInclusive<u8>| {
            if range.contains(&v) {
                Ok(())
            } else {
                Err(InvalidField::new(
                    field(name, i),
                    format!("{v} is outside {}..={}", range.start(), range.end()),
                ))
            }
        };
        for j in 0..6 {
            rules::joint_limits(self.min_angle_ddeg[j], self.max_angle_ddeg[j])
                .map_err(|problem| InvalidField::new(field("min_angle_ddeg", Some(j)), problem))?;
            let speed = self.max_speed_crad_s[j];
            if speed > MAX_SPEED_CEILING_CRAD_S {
                return Err(InvalidField::new(
                    field("max_speed_crad_s", Some(j)),
                    format!("{speed} is above the ceiling {MAX_SPEED_CEILING_CRAD_S}"),
                ));
            }
            let acc = self.max_acc_crad_s2[j];
            if acc > MAX_ACC_CEILING_CRAD_S2 {
                return Err(InvalidField::new(
                    field("max_acc_crad_s2", Some(j)),
                    format!("{acc} is above the ceiling {MAX_ACC_CEILING_CRAD_S2}"),
                ));
            }
            in_range(
                "collision_levels",
                Some(j),
                self.collision_levels[j],
                rules::COLLISION_LEVELS,
            )?;
        }
        in_range(
            "pendant_travel_pct",
            None,
            self.pendant_travel_pct,
            rules::PENDANT_TRAVEL_PCT,
        )?;
        in_range(
            "gripper_max_stroke_mm",
            None,
            self.gripper_max_stroke_mm,
            rules::GRIPPER_MAX_STROKE_MM,
        )?;
        in_range(
            "pendant_friction",
            None,
            self.pendant_friction,
            rules::PENDANT_FRICTION,
        )?;
        in_range(
            "install_position",
            None,
            self.install_position,
            rules::INSTALL_POSITIONS,
        )?;
        in_range("payload", None, self.payload, rules::PAYLOADS)?;
        for (name, v) in [
            ("feedback_offset", self.feedback_offset),
            ("control_offset", self.control_offset),
            ("target_offset", self.target_offset),
        ] {
            if !rules::is_id_offset(v) {
                return Err(InvalidField::new(
                    field(name, None),
                    format!("{v} is not one of 0, 16, 32 (0x00, 0x10, 0x20)"),
                ));
            }
        }
        Ok(())
    }

    /// Load from `path` (a missing file gives the defaults), checking the header (`kind`
    /// piper, `format`) and every value ([`Flash::validate`]).
    pub fn load(path: &Path) -> Result<Self, FlashError> {
        let Some(document) = state_file::load::<PiperStateFile>(path, STATE_FILE_KIND)? else {
            return Ok(Self::default());
        };
        document
            .flash
            .validate()
            .map_err(|invalid| FlashError::invalid(path, invalid))?;
        Ok(document.flash)
    }

    /// Write to `path` so that the file is always complete (see [`state_file::save`]).
    pub fn save(&self, path: &Path) -> Result<(), FlashError> {
        state_file::save(
            path,
            &PiperStateFile {
                kind: STATE_FILE_KIND.to_owned(),
                format: state_file::FORMAT,
                flash: self.clone(),
            },
        )
    }
}

/// The state file's layout: the header, then the flash.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PiperStateFile {
    /// [`STATE_FILE_KIND`].
    kind: String,
    /// [`state_file::FORMAT`].
    format: u32,
    /// The parameters.
    flash: Flash,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state_file::StateFileError;

    #[test]
    fn round_trips_through_a_file_and_reports_bad_json() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("piper.json");
        let mut f = Flash::default();
        f.max_angle_ddeg[3] = 500;
        f.collision_levels = [1, 2, 3, 4, 5, 6];
        f.save(&path).unwrap();
        assert_eq!(Flash::load(&path).unwrap(), f);
        std::fs::write(
            &path,
            "{\"kind\": \"piper\", \"format\": 1, \"flash\": {\n  \"payload\": true\n}}",
        )
        .unwrap();
        match Flash::load(&path) {
            Err(StateFileError::Syntax { line, .. }) => assert_eq!(line, 2),
            other => panic!("{other:?}"),
        }
        assert_eq!(
            Flash::load(&dir.path().join("missing.json")).unwrap(),
            Flash::default()
        );
    }

    /// Write a Piper state file whose flash is the defaults with `field` set to `value`.
    fn file_with(path: &Path, field: &str, value: serde_json::Value) {
        let mut flash = serde_json::to_value(Flash::default()).unwrap();
        flash[field] = value;
        let doc = serde_json::json!({"kind": "piper", "format": 1, "flash": flash});
        std::fs::write(path, doc.to_string()).unwrap();
    }

    #[test]
    fn a_file_is_refused_where_the_commands_would_refuse_naming_the_file_and_field() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("piper.json");
        let refused = |field: &str, value: serde_json::Value| {
            file_with(&path, field, value);
            match Flash::load(&path) {
                Err(e @ StateFileError::Invalid { .. }) => e.to_string(),
                other => panic!("{field}: expected a refusal, got {other:?}"),
            }
        };
        // D4: min above max panicked the core's clamp at the first move.
        let mut min = DEFAULT_MIN_ANGLE_DDEG.to_vec();
        min[2] = 100;
        let mut max = DEFAULT_MAX_ANGLE_DDEG.to_vec();
        max[2] = 0;
        file_with(&path, "max_angle_ddeg", serde_json::json!(max));
        let mut doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        doc["flash"]["min_angle_ddeg"] = serde_json::json!(min);
        std::fs::write(&path, doc.to_string()).unwrap();
        let err = Flash::load(&path).unwrap_err().to_string();
        assert!(
            err.contains("piper.json") && err.contains("flash.min_angle_ddeg[2]"),
            "{err}"
        );
        let err = refused("collision_levels", serde_json::json!([0, 0, 9, 0, 0, 0]));
        assert!(err.contains("flash.collision_levels[2]"), "{err}");
        let err = refused("pendant_friction", serde_json::json!(0));
        assert!(err.contains("flash.pendant_friction"), "{err}");
        let err = refused("control_offset", serde_json::json!(5));
        assert!(err.contains("flash.control_offset"), "{err}");
        let err = refused("max_speed_crad_s", serde_json::json!([301, 0, 0, 0, 0, 0]));
        assert!(err.contains("flash.max_speed_crad_s[0]"), "{err}");
        // The same values within the rules load.
        file_with(
            &path,
            "collision_levels",
            serde_json::json!([8, 0, 0, 0, 0, 0]),
        );
        assert_eq!(Flash::load(&path).unwrap().collision_levels[0], 8);
    }

    #[test]
    fn a_file_of_another_emulator_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("realman.json");
        std::fs::write(&path, r#"{"kind": "realman", "format": 1, "params": {}}"#).unwrap();
        let err = Flash::load(&path).unwrap_err().to_string();
        assert!(
            err.contains("realman.json") && err.contains("`kind`"),
            "{err}"
        );
    }
}
