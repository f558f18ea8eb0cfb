//! The controller's settings (what `save_device_info_all` keeps across a power cycle) and the
//! state file that holds them, written atomically (temporary file in the same directory, then
//! rename).

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::facts::{DhRow, ModelFacts};

/// Default end-effector limits restored by `set_arm_init` (docs/protocols/realman.md §8).
pub const INIT_LINE_SPEED_M_S: f64 = 0.25;
/// See [`INIT_LINE_SPEED_M_S`].
pub const INIT_LINE_ACC_M_S2: f64 = 1.6;
/// See [`INIT_LINE_SPEED_M_S`].
pub const INIT_ANGULAR_SPEED_RAD_S: f64 = 0.6;
/// See [`INIT_LINE_SPEED_M_S`].
pub const INIT_ANGULAR_ACC_RAD_S2: f64 = 4.0;

/// A named frame (tool or work) with its pose relative to the flange / base.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Frame name.
    pub name: String,
    /// Position, m.
    pub position_m: [f64; 3],
    /// Z-Y-X Euler angles, rad.
    pub euler_rad: [f64; 3],
    /// Tool payload, kg (0 for work frames).
    pub payload_kg: f64,
    /// Tool centre of mass, m.
    pub com_m: [f64; 3],
}

impl Frame {
    fn identity(name: &str) -> Self {
        Self {
            name: name.into(),
            position_m: [0.0; 3],
            euler_rad: [0.0; 3],
            payload_kg: 0.0,
            com_m: [0.0; 3],
        }
    }
}

/// Optional blocks of the UDP push (`custom` of `set_realtime_push`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct PushCustom {
    /// `joint_status.joint_speed`.
    pub joint_speed: bool,
    /// `lift_state`.
    pub lift_state: bool,
    /// `expand_state`.
    pub expand_state: bool,
    /// `arm_current_status`.
    pub arm_current_status: bool,
    /// `aloha_state`.
    pub aloha_state: bool,
    /// `hand` (the SDK's key for the hand block).
    pub hand: bool,
    /// `rm_plus_base`.
    pub rm_plus_base: bool,
    /// `rm_plus_state`.
    pub rm_plus_state: bool,
}

impl PushCustom {
    /// The documented flags, always reported by `get_realtime_push`.
    pub const DOCUMENTED: usize = 5;

    /// Wire key and value of every flag, in the controller's order (the documented ones
    /// first, then the SDK's extra keys).
    pub fn entries(&self) -> [(&'static str, bool); 8] {
        [
            ("joint_speed", self.joint_speed),
            ("lift_state", self.lift_state),
            ("expand_state", self.expand_state),
            ("arm_current_status", self.arm_current_status),
            ("aloha_state", self.aloha_state),
            ("hand", self.hand),
            ("rm_plus_base", self.rm_plus_base),
            ("rm_plus_state", self.rm_plus_state),
        ]
    }

    /// Set a flag by its wire key; false if the key is unknown.
    pub fn set(&mut self, key: &str, on: bool) -> bool {
        let slot = match key {
            "joint_speed" => &mut self.joint_speed,
            "lift_state" => &mut self.lift_state,
            "expand_state" => &mut self.expand_state,
            "arm_current_status" => &mut self.arm_current_status,
            "aloha_state" => &mut self.aloha_state,
            "hand" => &mut self.hand,
            "rm_plus_base" => &mut self.rm_plus_base,
            "rm_plus_state" => &mut self.rm_plus_state,
            _ => return false,
        };
        *slot = on;
        true
    }
}

/// UDP realtime push configuration (docs/protocols/realman.md §11).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PushConfig {
    /// Period in units of 5 ms.
    pub cycle: u32,
    /// Whether the push runs.
    pub enable: bool,
    /// Destination UDP port.
    pub port: u16,
    /// Frame of force data (−1: no force sensor).
    pub force_coordinate: i64,
    /// Destination IP; empty = every host holding a TCP connection.
    pub ip: String,
    /// Optional blocks.
    pub custom: PushCustom,
}

impl Default for PushConfig {
    fn default() -> Self {
        Self {
            cycle: 1,
            enable: true,
            port: 8089,
            force_coordinate: -1,
            ip: String::new(),
            custom: PushCustom::default(),
        }
    }
}

/// Every setting the controller keeps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// End-effector max line speed, m/s.
    pub line_speed_m_s: f64,
    /// End-effector max line acceleration, m/s².
    pub line_acc_m_s2: f64,
    /// End-effector max angular speed, rad/s.
    pub angular_speed_rad_s: f64,
    /// End-effector max angular acceleration, rad/s².
    pub angular_acc_rad_s2: f64,
    /// Collision detection stage 0–8.
    pub collision_stage: u8,
    /// Self-collision detection enabled.
    pub self_collision_enable: bool,
    /// MDH table reported by `get_DH_data`.
    pub dh: Vec<DhRow>,
    /// Joint zero offsets, degrees.
    pub zero_offset_deg: Vec<f64>,
    /// Lower joint limits, degrees.
    pub min_deg: Vec<f64>,
    /// Upper joint limits, degrees.
    pub max_deg: Vec<f64>,
    /// Joint speed limits, °/s.
    pub max_speed_deg_s: Vec<f64>,
    /// Joint acceleration limits, °/s².
    pub max_acc_deg_s2: Vec<f64>,
    /// Tool frames (the first is the default `Arm_Tip`).
    pub tool_frames: Vec<Frame>,
    /// Index of the current tool frame.
    pub current_tool: usize,
    /// Work frames (the first is the default `Base`).
    pub work_frames: Vec<Frame>,
    /// Index of the current work frame.
    pub current_work: usize,
    /// Installation angles `[rot, pitch, azimuth]`, degrees.
    pub install_pose_deg: [f64; 3],
    /// Realtime push.
    pub push: PushConfig,
    /// Joint positions when the state was last saved, degrees (the boot pose).
    pub joints_deg: Option<Vec<f64>>,
}

impl Params {
    /// Factory settings of a model.
    pub fn factory(facts: &ModelFacts) -> Self {
        Self {
            line_speed_m_s: INIT_LINE_SPEED_M_S,
            line_acc_m_s2: INIT_LINE_ACC_M_S2,
            angular_speed_rad_s: INIT_ANGULAR_SPEED_RAD_S,
            angular_acc_rad_s2: INIT_ANGULAR_ACC_RAD_S2,
            collision_stage: 0,
            self_collision_enable: false,
            dh: facts.dh.clone(),
            zero_offset_deg: vec![0.0; facts.dof],
            min_deg: facts.min_deg.clone(),
            max_deg: facts.max_deg.clone(),
            max_speed_deg_s: facts.max_speed_deg_s.clone(),
            max_acc_deg_s2: facts.max_acc_deg_s2.clone(),
            tool_frames: vec![Frame::identity("Arm_Tip")],
            current_tool: 0,
            work_frames: vec![Frame::identity("Base")],
            current_work: 0,
            install_pose_deg: [0.0; 3],
            push: PushConfig::default(),
            joints_deg: None,
        }
    }

    /// Whether the per-joint vectors match the model (a state file from another model does not).
    pub fn fits(&self, dof: usize) -> bool {
        [
            self.min_deg.len(),
            self.max_deg.len(),
            self.max_speed_deg_s.len(),
            self.max_acc_deg_s2.len(),
            self.zero_offset_deg.len(),
            self.dh.len(),
        ]
        .iter()
        .all(|n| *n == dof)
            && self.current_tool < self.tool_frames.len()
            && self.current_work < self.work_frames.len()
    }
}

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
    /// The file is not a Realman state file.
    #[error("state file {path}: line {line}, column {column}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// The file was saved for an arm with another number of joints.
    #[error("state file {path} is for another arm model (expected {dof} joints)")]
    WrongModel {
        /// The file.
        path: PathBuf,
        /// Joints of the running model.
        dof: usize,
    },
}

/// Load the settings; a missing file gives `None` (factory settings apply).
pub fn load(path: &Path, dof: usize) -> Result<Option<Params>, StateFileError> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(StateFileError::Io {
                path: path.into(),
                source,
            })
        }
    };
    let params: Params = serde_json::from_str(&text).map_err(|e| StateFileError::Format {
        path: path.into(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    if !params.fits(dof) {
        return Err(StateFileError::WrongModel {
            path: path.into(),
            dof,
        });
    }
    Ok(Some(params))
}

/// Write the settings atomically: a temporary file beside the target, synced, then renamed
/// over it, so a crash never leaves a half-written file.
pub fn save(path: &Path, params: &Params) -> Result<(), StateFileError> {
    let io = |source| StateFileError::Io {
        path: path.into(),
        source,
    };
    let text = serde_json::to_string_pretty(params).map_err(|e| StateFileError::Format {
        path: path.into(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(io)?;
    tmp.write_all(text.as_bytes()).map_err(io)?;
    tmp.as_file().sync_all().map_err(io)?;
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}
