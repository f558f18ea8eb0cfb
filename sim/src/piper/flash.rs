//! The master controller's non-volatile parameters ("flash"), optionally persisted to a JSON
//! state file so they survive emulator restarts.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

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
#[serde(default)]
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

/// Reading or writing the state file failed.
#[derive(Debug, thiserror::Error)]
pub enum FlashError {
    /// File I/O failed.
    #[error("state file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid JSON for [`Flash`].
    #[error("state file {path}:{line}:{column}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
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

    /// Load from `path`; a missing file gives the defaults.
    pub fn load(path: &Path) -> Result<Self, FlashError> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Self::default()),
            Err(source) => {
                return Err(FlashError::Io {
                    path: path.to_owned(),
                    source,
                })
            }
        };
        serde_json::from_str(&text).map_err(|e| FlashError::Parse {
            path: path.to_owned(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })
    }

    /// Write to `path` atomically (temporary file in the same directory, then rename).
    pub fn save(&self, path: &Path) -> Result<(), FlashError> {
        let io = |source| FlashError::Io {
            path: path.to_owned(),
            source,
        };
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| io(std::io::Error::other(e.to_string())))?;
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let tmp = PathBuf::from(tmp);
        std::fs::write(&tmp, text).map_err(io)?;
        std::fs::rename(&tmp, path).map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_a_file_and_reports_bad_json() {
        let dir = std::env::temp_dir().join(format!("armhil-flash-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("piper.json");
        let mut f = Flash::default();
        f.max_angle_ddeg[3] = 500;
        f.collision_levels = [1, 2, 3, 4, 5, 6];
        f.save(&path).unwrap();
        assert_eq!(Flash::load(&path).unwrap(), f);
        std::fs::write(&path, "{\n  \"payload\": true\n}").unwrap();
        match Flash::load(&path) {
            Err(FlashError::Parse { line, .. }) => assert_eq!(line, 2),
            other => panic!("{other:?}"),
        }
        assert_eq!(
            Flash::load(&dir.join("missing.json")).unwrap(),
            Flash::default()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
