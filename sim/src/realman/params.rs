//! The controller's settings (what `save_device_info_all` keeps across a power cycle) and the
//! state file that holds them, written atomically (temporary file in the same directory, then
//! rename).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::facts::{DhRow, ModelFacts};
use super::ioports::IoState;
use crate::state_file::{self, InvalidField};

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
#[serde(deny_unknown_fields)]
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
#[serde(deny_unknown_fields)]
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
    /// `io_state`: armhil's own block with the IO ports (no Realman key carries them; off
    /// unless a client asks, so a vendor client sees only documented keys).
    #[serde(default)]
    pub io_state: bool,
}

impl PushCustom {
    /// The documented flags, always reported by `get_realtime_push`.
    pub const DOCUMENTED: usize = 5;

    /// Wire key and value of every flag, in the controller's order (the documented ones
    /// first, then the SDK's extra keys).
    pub fn entries(&self) -> [(&'static str, bool); 9] {
        [
            ("joint_speed", self.joint_speed),
            ("lift_state", self.lift_state),
            ("expand_state", self.expand_state),
            ("arm_current_status", self.arm_current_status),
            ("aloha_state", self.aloha_state),
            ("hand", self.hand),
            ("rm_plus_base", self.rm_plus_base),
            ("rm_plus_state", self.rm_plus_state),
            ("io_state", self.io_state),
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
            "io_state" => &mut self.io_state,
            _ => return false,
        };
        *slot = on;
        true
    }
}

/// UDP realtime push configuration (docs/protocols/realman.md §11).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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
#[serde(deny_unknown_fields)]
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
    /// IO ports: modes, output levels, analog outputs, supplies (absent in files written
    /// before the ports were emulated: power-on state).
    #[serde(default)]
    pub io: IoState,
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
            io: IoState::default(),
        }
    }
}

/// Why the state file could not be read, checked or written (it names the file and field).
pub type StateFileError = crate::state_file::StateFileError;

/// The value of `kind` in a Realman state file.
pub const STATE_FILE_KIND: &str = "realman";

/// What the controller's set commands accept, shared by the commands and the state-file check
/// so the two can never disagree (a file can only hold what a command could have stored).
pub mod rules {
    use std::net::Ipv4Addr;
    use std::ops::RangeInclusive;

    /// `set_collision_stage` stages.
    pub const COLLISION_STAGES: RangeInclusive<u8> = 0..=8;
    /// `set_realtime_push` cycles, units of 5 ms.
    pub const PUSH_CYCLES: RangeInclusive<u32> = 1..=100;
    /// Most tool frames the controller stores (`set_manual_tool_frame`).
    pub const MAX_TOOL_FRAMES: usize = 10;

    /// Why a joint's lower/upper limit pair (degrees) is refused by `set_joint_min_pos` /
    /// `set_joint_max_pos`, if it is: the lower limit must stay below the upper.
    pub fn joint_limits(min_deg: f64, max_deg: f64) -> Result<(), String> {
        if min_deg < max_deg {
            Ok(())
        } else {
            Err(format!(
                "lower limit {min_deg}° is not below upper limit {max_deg}°"
            ))
        }
    }

    /// Whether a speed or acceleration limit is accepted (positive).
    pub fn positive_limit(value: f64) -> bool {
        value > 0.0 && value.is_finite()
    }

    /// Whether a UDP port is accepted as the push's destination (not 0).
    pub fn push_port(port: u16) -> bool {
        port > 0
    }

    /// Whether `ip` is accepted as the push's destination: empty (every connected client) or
    /// an IPv4 address.
    pub fn push_ip(ip: &str) -> bool {
        ip.is_empty() || ip.parse::<Ipv4Addr>().is_ok()
    }

    /// Whether a frame name is accepted (1 to 10 bytes).
    pub fn frame_name(name: &str) -> bool {
        !name.is_empty() && name.len() <= 10
    }
}

impl Params {
    /// Check every setting against what the commands would have stored for an arm with
    /// `dof` joints ([`rules`]); fields are named as in the state file (`params.min_deg[2]`).
    pub fn validate(&self, dof: usize) -> Result<(), InvalidField> {
        let bad = |field: String, problem: String| Err(InvalidField::new(field, problem));
        for (name, len) in [
            ("min_deg", self.min_deg.len()),
            ("max_deg", self.max_deg.len()),
            ("max_speed_deg_s", self.max_speed_deg_s.len()),
            ("max_acc_deg_s2", self.max_acc_deg_s2.len()),
            ("zero_offset_deg", self.zero_offset_deg.len()),
            ("dh", self.dh.len()),
        ] {
            if len != dof {
                return bad(
                    format!("params.{name}"),
                    format!("{len} joints, this arm model has {dof} (a file of another model?)"),
                );
            }
        }
        if let Some(joints) = &self.joints_deg {
            if joints.len() != dof {
                return bad(
                    "params.joints_deg".into(),
                    format!("{} joints, this arm model has {dof}", joints.len()),
                );
            }
        }
        for j in 0..dof {
            rules::joint_limits(self.min_deg[j], self.max_deg[j])
                .or_else(|problem| bad(format!("params.min_deg[{j}]"), problem))?;
            for (name, value) in [
                ("max_speed_deg_s", self.max_speed_deg_s[j]),
                ("max_acc_deg_s2", self.max_acc_deg_s2[j]),
            ] {
                if !rules::positive_limit(value) {
                    return bad(
                        format!("params.{name}[{j}]"),
                        format!("{value} is not positive"),
                    );
                }
            }
        }
        for (name, value) in [
            ("line_speed_m_s", self.line_speed_m_s),
            ("line_acc_m_s2", self.line_acc_m_s2),
            ("angular_speed_rad_s", self.angular_speed_rad_s),
            ("angular_acc_rad_s2", self.angular_acc_rad_s2),
        ] {
            if !rules::positive_limit(value) {
                return bad(format!("params.{name}"), format!("{value} is not positive"));
            }
        }
        if !rules::COLLISION_STAGES.contains(&self.collision_stage) {
            return bad(
                "params.collision_stage".into(),
                format!("{} is outside 0..=8", self.collision_stage),
            );
        }
        for (name, frames, current, most) in [
            (
                "tool_frames",
                &self.tool_frames,
                self.current_tool,
                rules::MAX_TOOL_FRAMES,
            ),
            (
                "work_frames",
                &self.work_frames,
                self.current_work,
                usize::MAX,
            ),
        ] {
            if frames.is_empty() || frames.len() > most {
                return bad(
                    format!("params.{name}"),
                    format!("{} frames (1 to {most})", frames.len()),
                );
            }
            if let Some((i, f)) = frames
                .iter()
                .enumerate()
                .find(|(_, f)| !rules::frame_name(&f.name))
            {
                return bad(
                    format!("params.{name}[{i}].name"),
                    format!("{:?} is not 1 to 10 bytes", f.name),
                );
            }
            if current >= frames.len() {
                let which = if name == "tool_frames" {
                    "current_tool"
                } else {
                    "current_work"
                };
                return bad(
                    format!("params.{which}"),
                    format!("{current} is not one of the {} frames", frames.len()),
                );
            }
        }
        let push = &self.push;
        if !rules::PUSH_CYCLES.contains(&push.cycle) {
            return bad(
                "params.push.cycle".into(),
                format!("{} is outside 1..=100", push.cycle),
            );
        }
        if !rules::push_port(push.port) {
            return bad("params.push.port".into(), "0 is not a port".into());
        }
        if !rules::push_ip(&push.ip) {
            return bad(
                "params.push.ip".into(),
                format!("{:?} is neither empty nor an IPv4 address", push.ip),
            );
        }
        self.io.validate()
    }
}

/// The layout on disk: the header, then the settings.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Document {
    kind: String,
    format: u32,
    params: Params,
}

/// Load the settings for an arm with `dof` joints, checking the header (`kind` realman,
/// `format`) and every value ([`Params::validate`]); a missing file gives `None` (factory
/// settings apply).
pub fn load(path: &Path, dof: usize) -> Result<Option<Params>, StateFileError> {
    let Some(document) = state_file::load::<Document>(path, STATE_FILE_KIND)? else {
        return Ok(None);
    };
    document
        .params
        .validate(dof)
        .map_err(|invalid| StateFileError::invalid(path, invalid))?;
    Ok(Some(document.params))
}

/// Write the settings so that the file is always complete (see [`state_file::save`]).
pub fn save(path: &Path, params: &Params) -> Result<(), StateFileError> {
    state_file::save(
        path,
        &Document {
            kind: STATE_FILE_KIND.to_owned(),
            format: state_file::FORMAT,
            params: params.clone(),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::realman::model::ArmModel;

    fn factory() -> Params {
        Params::factory(&ModelFacts::of(&ArmModel::rm65b()))
    }

    #[test]
    fn saved_settings_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("realman.json");
        let mut params = factory();
        params.line_speed_m_s = 0.4;
        save(&path, &params).unwrap();
        assert_eq!(load(&path, 6).unwrap(), Some(params));
    }

    #[test]
    fn settings_no_command_would_store_are_refused_naming_the_file_and_field() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("realman.json");
        let refused = |tune: &dyn Fn(&mut Params), dof: usize| {
            let mut params = factory();
            tune(&mut params);
            save(&path, &params).unwrap();
            let err = load(&path, dof).unwrap_err().to_string();
            assert!(err.contains("realman.json"), "{err}");
            err
        };
        // D4: min above max panicked the core at the first move.
        let err = refused(&|p| p.min_deg[1] = p.max_deg[1] + 10.0, 6);
        assert!(err.contains("params.min_deg[1]"), "{err}");
        let err = refused(&|p| p.max_speed_deg_s[0] = 0.0, 6);
        assert!(err.contains("params.max_speed_deg_s[0]"), "{err}");
        let err = refused(&|p| p.collision_stage = 9, 6);
        assert!(err.contains("params.collision_stage"), "{err}");
        let err = refused(&|p| p.push.cycle = 0, 6);
        assert!(err.contains("params.push.cycle"), "{err}");
        let err = refused(&|p| p.push.ip = "attacker.example".into(), 6);
        assert!(err.contains("params.push.ip"), "{err}");
        let err = refused(&|p| p.io.modes[0] = 99, 6);
        assert!(err.contains("params.io.modes[0]"), "{err}");
        let err = refused(&|p| p.current_tool = 3, 6);
        assert!(err.contains("params.current_tool"), "{err}");
        // A file of a 6-joint arm given to a 7-joint one.
        let err = refused(&|_| {}, 7);
        assert!(err.contains("params.min_deg") && err.contains("7"), "{err}");
    }

    #[test]
    fn a_piper_file_is_refused_by_its_kind() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("piper.json");
        crate::piper::Flash::default().save(&path).unwrap();
        let err = load(&path, 6).unwrap_err().to_string();
        assert!(
            err.contains("piper.json") && err.contains("`kind`") && err.contains("\"piper\""),
            "{err}"
        );
    }
}
