//! Request encoders: typed SI arguments in, compact JSON + CRLF out (docs/protocols/realman.md
//! §3–§11), together with how the reply is recognised.
//!
//! Field order follows the protocol document; the fixtures pin the exact bytes.

mod io;
mod peripherals;
pub use io::*;
pub use peripherals::*;

use serde::Serialize;

use super::types::{Axis, Connect, Direction, Pose, QuatPose, Smoothing};
use super::units::{all_to_wire, to_wire, MILLI, M_TO_UM, QUAT, RAD_S_TO_MILLI_RPM, RAD_TO_MDEG};
use super::EncodeError;

/// How a reply is tagged: by `"command"` or by `"state"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Tag {
    /// `{"command":"<name>", …}`.
    Command(&'static str),
    /// `{"state":"<name>", …}`.
    State(&'static str),
}

/// What a request expects back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expect {
    /// Nothing (passthrough streaming on a 3rd-generation controller).
    Nothing,
    /// A reply with `tag` whose boolean `key` says whether the command was accepted. `None`:
    /// the key is not documented; the first boolean field is taken.
    Flag {
        /// Reply tag.
        tag: Tag,
        /// Result key.
        key: Option<&'static str>,
    },
    /// A data reply with `tag`, decoded by the caller.
    Data {
        /// Reply tag.
        tag: Tag,
    },
}

impl Expect {
    /// The reply tag, if any reply is expected.
    pub fn tag(&self) -> Option<Tag> {
        match *self {
            Self::Nothing => None,
            Self::Flag { tag, .. } | Self::Data { tag } => Some(tag),
        }
    }
}

/// An encoded request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// The command name (for errors and logs).
    pub command: &'static str,
    /// Exact bytes to send (compact JSON + CRLF).
    pub wire: String,
    /// How its reply is recognised.
    pub expect: Expect,
}

/// Builds `{"command":"…",…}` with fields in insertion order.
struct Obj {
    command: &'static str,
    text: String,
}

impl Obj {
    fn new(command: &'static str) -> Self {
        Self {
            command,
            text: format!("{{\"command\":\"{command}\""),
        }
    }

    fn field<T: Serialize + ?Sized>(mut self, key: &str, value: &T) -> Self {
        // Serialising integers, bools, strings and derived structs cannot fail.
        let json = serde_json::to_string(value).unwrap_or_else(|_| "null".into());
        self.text.push_str(&format!(",\"{key}\":{json}"));
        self
    }

    fn done(self, expect: Expect) -> Request {
        Request {
            command: self.command,
            wire: self.text + "}\r\n",
            expect,
        }
    }

    fn flag(self, tag: Tag, key: &'static str) -> Request {
        self.done(Expect::Flag {
            tag,
            key: Some(key),
        })
    }

    /// Setter whose reply echoes the command name with result `key`.
    fn echo(self, key: &'static str) -> Request {
        let tag = Tag::Command(self.command);
        self.flag(tag, key)
    }
}

fn query(command: &'static str, tag: Tag) -> Request {
    Obj::new(command).done(Expect::Data { tag })
}

fn percent(field: &'static str, v: u8, min: u8, max: u8) -> Result<u8, EncodeError> {
    if (min..=max).contains(&v) {
        Ok(v)
    } else {
        Err(EncodeError::OutOfRange {
            field,
            value: v as i64,
            min: min as i64,
            max: max as i64,
        })
    }
}

fn ranged(field: &'static str, v: i64, min: i64, max: i64) -> Result<i64, EncodeError> {
    if (min..=max).contains(&v) {
        Ok(v)
    } else {
        Err(EncodeError::OutOfRange {
            field,
            value: v,
            min,
            max,
        })
    }
}

fn joints(values_rad: &[f64]) -> Result<Vec<i64>, EncodeError> {
    if !(1..=7).contains(&values_rad.len()) {
        return Err(EncodeError::JointCount {
            got: values_rad.len(),
        });
    }
    all_to_wire("joint", values_rad, RAD_TO_MDEG)
}

/// Pose as `[x, y, z (0.001 mm), rx, ry, rz (0.001 rad)]`.
pub(crate) fn pose_wire(pose: &Pose) -> Result<Vec<i64>, EncodeError> {
    let mut out = all_to_wire("pose.position", &pose.position_m, M_TO_UM)?;
    out.extend(all_to_wire("pose.euler", &pose.euler_rad, MILLI)?);
    Ok(out)
}

fn joint_index(joint: u8) -> Result<i64, EncodeError> {
    ranged("joint number", joint as i64, 1, 7)
}

// ---- the 11 handshake queries and other read-only queries ----

macro_rules! queries {
    ($( $fn:ident => $cmd:literal, $kind:ident($tag:literal); )*) => {
        $(
            #[doc = concat!("`", $cmd, "` → `", stringify!($kind), "(\"", $tag, "\")`.")]
            pub fn $fn() -> Request {
                query($cmd, Tag::$kind($tag))
            }
        )*
    };
}

queries! {
    get_arm_software_info => "get_arm_software_info", Command("arm_software_info");
    get_arm_current_trajectory => "get_arm_current_trajectory", State("arm_current_trajectory");
    get_realtime_push => "get_realtime_push", Command("get_realtime_push");
    get_current_work_frame => "get_current_work_frame", State("current_work_frame");
    get_current_tool_frame => "get_current_tool_frame", State("current_tool_frame");
    get_install_pose => "get_install_pose", State("install_pose");
    get_joint_min_pos => "get_joint_min_pos", State("joint_min_pos");
    get_joint_max_pos => "get_joint_max_pos", State("joint_max_pos");
    get_joint_max_acc => "get_joint_max_acc", State("joint_max_acc");
    get_joint_max_speed => "get_joint_max_speed", State("joint_max_speed");
    get_dh_data => "get_DH_data", Command("get_DH_data");
    get_arm_power_state => "get_arm_power_state", State("arm_power_state");
    get_joint_err_flag => "get_joint_err_flag", State("joint_err_flag");
    get_current_arm_state => "get_current_arm_state", State("current_arm_state");
    get_joint_degree => "get_joint_degree", State("joint_degree");
    get_arm_all_state => "get_arm_all_state", State("arm_all_state");
    get_controller_state => "get_controller_state", State("controller_state");
    get_current_joint_temperature => "get_current_joint_temperature", State("current_joint_temperature");
    get_current_joint_current => "get_current_joint_current", State("current_joint_current");
    get_current_joint_voltage => "get_current_joint_voltage", State("current_joint_voltage");
    get_arm_max_line_speed => "get_arm_max_line_speed", State("arm_max_line_speed");
    get_arm_max_line_acc => "get_arm_max_line_acc", State("arm_max_line_acc");
    get_arm_max_angular_speed => "get_arm_max_angular_speed", State("arm_max_angular_speed");
    get_arm_max_angular_acc => "get_arm_max_angular_acc", State("arm_max_angular_acc");
    get_collision_stage => "get_collision_stage", State("get_collision_stage");
    get_self_collision_enable => "get_self_collision_enable", Command("get_self_collision_enable");
    get_gripper_state => "get_gripper_state", Command("get_gripper_state");
}

/// The SDK's connect handshake, in its order (docs/protocols/realman.md §1).
pub fn handshake_queries() -> [Request; 11] {
    [
        get_arm_software_info(),
        get_arm_current_trajectory(),
        get_realtime_push(),
        get_current_work_frame(),
        get_current_tool_frame(),
        get_install_pose(),
        get_joint_min_pos(),
        get_joint_max_pos(),
        get_joint_max_acc(),
        get_joint_max_speed(),
        get_dh_data(),
    ]
}

// ---- planned motion ----

/// Speed, blend radius and queueing shared by planned moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MoveOpts {
    /// Speed, percent of the maximum (1..=100).
    pub speed_percent: u8,
    /// Blend radius, percent (0..=100); only effective when queued.
    pub blend_percent: u8,
    /// Run now or queue with the next command.
    pub connect: Connect,
}

impl MoveOpts {
    /// Run now at `speed_percent`, no blending.
    pub fn speed(speed_percent: u8) -> Self {
        Self {
            speed_percent,
            blend_percent: 0,
            connect: Connect::Start,
        }
    }
}

fn planned(
    command: &'static str,
    key: &str,
    target: impl Serialize,
    o: MoveOpts,
) -> Result<Obj, EncodeError> {
    let v = percent("v", o.speed_percent, 1, 100)?;
    let r = percent("r", o.blend_percent, 0, 100)?;
    Ok(Obj::new(command)
        .field(key, &target)
        .field("v", &v)
        .field("r", &r))
}

/// `movej`: joint-space move to `joints_rad`.
pub fn movej(joints_rad: &[f64], o: MoveOpts) -> Result<Request, EncodeError> {
    let obj = planned("movej", "joint", joints(joints_rad)?, o)?;
    Ok(obj
        .field("trajectory_connect", &o.connect.wire())
        .echo("receive_state"))
}

/// `movel`: straight-line move to `pose`.
pub fn movel(pose: &Pose, o: MoveOpts) -> Result<Request, EncodeError> {
    let obj = planned("movel", "pose", pose_wire(pose)?, o)?;
    Ok(obj
        .field("trajectory_connect", &o.connect.wire())
        .echo("receive_state"))
}

/// `movej_p`: joint-space move to a Cartesian `pose`.
pub fn movej_p(pose: &Pose, o: MoveOpts) -> Result<Request, EncodeError> {
    let obj = planned("movej_p", "pose", pose_wire(pose)?, o)?;
    Ok(obj
        .field("trajectory_connect", &o.connect.wire())
        .echo("receive_state"))
}

/// `moves`: one spline point (at least three queued points, the last with [`Connect::Start`]).
pub fn moves(pose: &Pose, o: MoveOpts) -> Result<Request, EncodeError> {
    let obj = planned("moves", "pose", pose_wire(pose)?, o)?;
    Ok(obj
        .field("trajectory_connect", &o.connect.wire())
        .echo("receive_state"))
}

#[derive(Serialize)]
struct ViaTo {
    pose_via: Vec<i64>,
    pose_to: Vec<i64>,
}

/// `movec`: arc through `via` to `to`, `loops` extra full turns.
pub fn movec(via: &Pose, to: &Pose, loops: u32, o: MoveOpts) -> Result<Request, EncodeError> {
    let target = ViaTo {
        pose_via: pose_wire(via)?,
        pose_to: pose_wire(to)?,
    };
    let obj = planned("movec", "pose", target, o)?;
    Ok(obj
        .field("loop", &loops)
        .field("trajectory_connect", &o.connect.wire())
        .echo("receive_state"))
}

/// `set_joint_step`: step joint `joint` (1-based) by `step_rad` at `speed_percent`.
pub fn set_joint_step(joint: u8, step_rad: f64, speed_percent: u8) -> Result<Request, EncodeError> {
    let step = [
        joint_index(joint)?,
        to_wire("joint_step", step_rad, RAD_TO_MDEG)?,
    ];
    let v = percent("v", speed_percent, 1, 100)?;
    Ok(Obj::new("set_joint_step")
        .field("joint_step", &step)
        .field("v", &v)
        .echo("receive_state"))
}

/// `set_pos_step`: step the tool `step_m` along `axis`.
pub fn set_pos_step(axis: Axis, step_m: f64, speed_percent: u8) -> Result<Request, EncodeError> {
    let v = percent("v", speed_percent, 1, 100)?;
    Ok(Obj::new("set_pos_step")
        .field("step_type", &format!("{}_step", axis.letter()))
        .field("step", &to_wire("step", step_m, M_TO_UM)?)
        .field("v", &v)
        .echo("receive_state"))
}

/// `set_ort_step`: rotate the tool `step_rad` about `axis`.
pub fn set_ort_step(axis: Axis, step_rad: f64, speed_percent: u8) -> Result<Request, EncodeError> {
    let v = percent("v", speed_percent, 1, 100)?;
    Ok(Obj::new("set_ort_step")
        .field("step_type", &format!("r{}_step", axis.letter()))
        .field("step", &to_wire("step", step_rad, MILLI)?)
        .field("v", &v)
        .echo("receive_state"))
}

/// `set_joint_teach`: jog joint `joint` until [`set_stop_teach`].
pub fn set_joint_teach(
    joint: u8,
    dir: Direction,
    speed_percent: u8,
) -> Result<Request, EncodeError> {
    let v = percent("v", speed_percent, 1, 100)?;
    Ok(Obj::new("set_joint_teach")
        .field("teach_joint", &joint_index(joint)?)
        .field("direction", dir.wire())
        .field("v", &v)
        .echo("joint_teach"))
}

/// `set_pos_teach`: jog the tool position along `axis`.
pub fn set_pos_teach(
    axis: Axis,
    dir: Direction,
    speed_percent: u8,
) -> Result<Request, EncodeError> {
    let v = percent("v", speed_percent, 1, 100)?;
    Ok(Obj::new("set_pos_teach")
        .field("teach_type", axis.letter())
        .field("direction", dir.wire())
        .field("v", &v)
        .echo("pos_teach"))
}

/// `set_ort_teach`: jog the tool orientation about `axis`.
pub fn set_ort_teach(
    axis: Axis,
    dir: Direction,
    speed_percent: u8,
) -> Result<Request, EncodeError> {
    let v = percent("v", speed_percent, 1, 100)?;
    Ok(Obj::new("set_ort_teach")
        .field("teach_type", &format!("r{}", axis.letter()))
        .field("direction", dir.wire())
        .field("v", &v)
        .echo("ort_teach"))
}

/// `set_stop_teach`: end a jog.
pub fn set_stop_teach() -> Request {
    Obj::new("set_stop_teach").echo("stop_teach")
}

// ---- passthrough ----

fn smoothing(s: Smoothing) -> Result<(u8, u16), EncodeError> {
    match s {
        Smoothing::Raw => Ok((0, 0)),
        Smoothing::CurveFit(r) => Ok((1, ranged("radio", r as i64, 0, 100)? as u16)),
        Smoothing::Filter(r) => Ok((2, ranged("radio", r as i64, 0, 1000)? as u16)),
    }
}

/// `movej_canfd`: joint passthrough; no reply on a 3rd-generation controller.
pub fn movej_canfd(joints_rad: &[f64], follow: bool, s: Smoothing) -> Result<Request, EncodeError> {
    let (mode, radio) = smoothing(s)?;
    Ok(Obj::new("movej_canfd")
        .field("joint", &joints(joints_rad)?)
        .field("follow", &follow)
        .field("trajectory_mode", &mode)
        .field("radio", &radio)
        .done(Expect::Nothing))
}

/// A passthrough Cartesian target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CartesianTarget {
    /// Euler form (`pose`).
    Euler(Pose),
    /// Quaternion form (`pose_quat`).
    Quat(QuatPose),
}

fn cartesian(obj: Obj, target: &CartesianTarget) -> Result<Obj, EncodeError> {
    Ok(match target {
        CartesianTarget::Euler(p) => obj.field("pose", &pose_wire(p)?),
        CartesianTarget::Quat(q) => {
            let mut v = all_to_wire("pose_quat.position", &q.position_m, M_TO_UM)?;
            v.extend(all_to_wire(
                "pose_quat.quaternion",
                &q.quaternion_wxyz,
                QUAT,
            )?);
            obj.field("pose_quat", &v)
        }
    })
}

/// `movep_canfd`: Cartesian passthrough; no reply on a 3rd-generation controller.
pub fn movep_canfd(
    target: &CartesianTarget,
    follow: bool,
    s: Smoothing,
) -> Result<Request, EncodeError> {
    let (mode, radio) = smoothing(s)?;
    Ok(cartesian(Obj::new("movep_canfd"), target)?
        .field("follow", &follow)
        .field("trajectory_mode", &mode)
        .field("radio", &radio)
        .done(Expect::Nothing))
}

/// `movej_follow`: online-planned follow of a joint target; no reply.
pub fn movej_follow(joints_rad: &[f64]) -> Result<Request, EncodeError> {
    Ok(Obj::new("movej_follow")
        .field("joint", &joints(joints_rad)?)
        .done(Expect::Nothing))
}

/// `movep_follow`: online-planned follow of a Cartesian target; no reply.
pub fn movep_follow(target: &CartesianTarget) -> Result<Request, EncodeError> {
    Ok(cartesian(Obj::new("movep_follow"), target)?.done(Expect::Nothing))
}

// ---- stop / pause ----

macro_rules! plain_setters {
    ($( $fn:ident => $cmd:literal, $key:literal; )*) => {
        $(
            #[doc = concat!("`", $cmd, "` → result key `", $key, "`.")]
            pub fn $fn() -> Request {
                Obj::new($cmd).echo($key)
            }
        )*
    };
}

plain_setters! {
    set_arm_stop => "set_arm_stop", "arm_stop";
    set_arm_slow_stop => "set_arm_slow_stop", "arm_slow_stop";
    set_arm_pause => "set_arm_pause", "arm_pause";
    set_arm_continue => "set_arm_continue", "arm_continue";
    set_delete_current_trajectory => "set_delete_current_trajectory", "delete_current_trajectory";
    set_arm_delete_trajectory => "set_arm_delete_trajectory", "arm_delete_trajectory";
    set_arm_init => "set_arm_init", "arm_init";
    set_dh_data_default => "set_DH_data_default", "set_state";
    clear_system_err => "clear_system_err", "clear_state";
}

/// `save_device_info_all` (2nd generation: write parameters to flash). The result key is not
/// documented, so the first boolean of the reply is taken.
pub fn save_device_info_all() -> Request {
    Obj::new("save_device_info_all").done(Expect::Flag {
        tag: Tag::Command("save_device_info_all"),
        key: None,
    })
}

// ---- motion parameters (end effector) ----

fn positive(field: &'static str, v: f64) -> Result<f64, EncodeError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(EncodeError::NotEncodable { field, value: v })
    }
}

/// `set_arm_max_line_speed` in m/s.
pub fn set_arm_max_line_speed(m_s: f64) -> Result<Request, EncodeError> {
    let v = to_wire("arm_line_speed", positive("arm_line_speed", m_s)?, MILLI)?;
    Ok(Obj::new("set_arm_max_line_speed")
        .field("arm_line_speed", &v)
        .echo("arm_line_speed"))
}

/// `set_arm_max_line_acc` in m/s².
pub fn set_arm_max_line_acc(m_s2: f64) -> Result<Request, EncodeError> {
    let v = to_wire("arm_line_acc", positive("arm_line_acc", m_s2)?, MILLI)?;
    Ok(Obj::new("set_arm_max_line_acc")
        .field("arm_line_acc", &v)
        .echo("arm_line_acc"))
}

/// `set_arm_max_angular_speed` in rad/s.
pub fn set_arm_max_angular_speed(rad_s: f64) -> Result<Request, EncodeError> {
    let v = to_wire(
        "arm_angular_speed",
        positive("arm_angular_speed", rad_s)?,
        MILLI,
    )?;
    Ok(Obj::new("set_arm_max_angular_speed")
        .field("arm_angular_speed", &v)
        .echo("arm_angular_speed"))
}

/// `set_arm_max_angular_acc` in rad/s².
pub fn set_arm_max_angular_acc(rad_s2: f64) -> Result<Request, EncodeError> {
    let v = to_wire(
        "arm_angular_acc",
        positive("arm_angular_acc", rad_s2)?,
        MILLI,
    )?;
    Ok(Obj::new("set_arm_max_angular_acc")
        .field("arm_angular_acc", &v)
        .echo("arm_angular_acc"))
}

/// `set_collision_stage` 0..=8 (higher = more sensitive). The reply is matched on the command
/// name with key `collision_state` (what the vendor SDK accepts).
pub fn set_collision_stage(stage: u8) -> Result<Request, EncodeError> {
    let stage = ranged("collision_stage", stage as i64, 0, 8)?;
    Ok(Obj::new("set_collision_stage")
        .field("collision_stage", &stage)
        .echo("collision_state"))
}

/// `set_self_collision_enable`.
pub fn set_self_collision_enable(enable: bool) -> Request {
    Obj::new("set_self_collision_enable")
        .field("set_enable", &enable)
        .echo("set_state")
}

/// One row of the DH table (modified DH).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DhRow {
    /// alpha in radians.
    pub alpha_rad: f64,
    /// a in metres.
    pub a_m: f64,
    /// d in metres.
    pub d_m: f64,
    /// Joint offset in radians.
    pub offset_rad: f64,
}

const JOINT_KEYS: [&str; 7] = [
    "joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6", "joint_7",
];

/// `set_DH_data` with one row per joint (6 or 7).
pub fn set_dh_data(rows: &[DhRow]) -> Result<Request, EncodeError> {
    if !(6..=7).contains(&rows.len()) {
        return Err(EncodeError::JointCount { got: rows.len() });
    }
    let mut obj = Obj::new("set_DH_data");
    for (row, key) in rows.iter().zip(JOINT_KEYS) {
        let v = [
            to_wire("alpha", row.alpha_rad, RAD_TO_MDEG)?,
            to_wire("a", row.a_m, M_TO_UM)?,
            to_wire("d", row.d_m, M_TO_UM)?,
            to_wire("offset", row.offset_rad, RAD_TO_MDEG)?,
        ];
        obj = obj.field(key, &v);
    }
    Ok(obj.echo("set_state"))
}

/// `set_joint_zero_offset`, one offset per joint in radians.
pub fn set_joint_zero_offset(offsets_rad: &[f64]) -> Result<Request, EncodeError> {
    Ok(Obj::new("set_joint_zero_offset")
        .field("offset", &joints(offsets_rad)?)
        .echo("set_state"))
}

// ---- power, joints, frames ----

/// `set_arm_power`.
pub fn set_arm_power(on: bool) -> Request {
    Obj::new("set_arm_power")
        .field("arm_power", &u8::from(on))
        .echo("arm_power")
}

/// `set_joint_en_state` for joint `joint` (1-based).
pub fn set_joint_en_state(joint: u8, enable: bool) -> Result<Request, EncodeError> {
    let v = [joint_index(joint)?, i64::from(enable)];
    Ok(Obj::new("set_joint_en_state")
        .field("joint_en_state", &v)
        .echo("joint_en_state"))
}

fn joint_pair(command: &'static str, joint: u8, value: i64) -> Result<Request, EncodeError> {
    let v = [joint_index(joint)?, value];
    Ok(Obj::new(command)
        .field(command.trim_start_matches("set_"), &v)
        .echo(match command {
            "set_joint_min_pos" => "joint_min_pos",
            "set_joint_max_pos" => "joint_max_pos",
            "set_joint_max_speed" => "joint_max_speed",
            _ => "joint_max_acc",
        }))
}

/// `set_joint_min_pos` (joint must be disabled).
pub fn set_joint_min_pos(joint: u8, rad: f64) -> Result<Request, EncodeError> {
    joint_pair(
        "set_joint_min_pos",
        joint,
        to_wire("joint_min_pos", rad, RAD_TO_MDEG)?,
    )
}

/// `set_joint_max_pos` (joint must be disabled).
pub fn set_joint_max_pos(joint: u8, rad: f64) -> Result<Request, EncodeError> {
    joint_pair(
        "set_joint_max_pos",
        joint,
        to_wire("joint_max_pos", rad, RAD_TO_MDEG)?,
    )
}

/// `set_joint_max_speed` in rad/s (sent as 0.001 RPM).
pub fn set_joint_max_speed(joint: u8, rad_s: f64) -> Result<Request, EncodeError> {
    let v = to_wire(
        "joint_max_speed",
        positive("joint_max_speed", rad_s)?,
        RAD_S_TO_MILLI_RPM,
    )?;
    joint_pair("set_joint_max_speed", joint, v)
}

/// `set_joint_max_acc` in rad/s² (sent as 0.001 RPM/s).
pub fn set_joint_max_acc(joint: u8, rad_s2: f64) -> Result<Request, EncodeError> {
    let v = to_wire(
        "joint_max_acc",
        positive("joint_max_acc", rad_s2)?,
        RAD_S_TO_MILLI_RPM,
    )?;
    joint_pair("set_joint_max_acc", joint, v)
}

/// `set_joint_clear_err` for joint `joint`.
pub fn set_joint_clear_err(joint: u8) -> Result<Request, EncodeError> {
    Ok(Obj::new("set_joint_clear_err")
        .field("joint_clear_err", &joint_index(joint)?)
        .echo("joint_clear_err"))
}

/// `set_install_pose`: rotation, pitch, azimuth in radians (sent in whole degrees).
pub fn set_install_pose(rot_pitch_azimuth_rad: [f64; 3]) -> Result<Request, EncodeError> {
    let v = all_to_wire(
        "install pose",
        &rot_pitch_azimuth_rad,
        180.0 / std::f64::consts::PI,
    )?;
    Ok(Obj::new("set_install_pose")
        .field("pose", &v)
        .echo("set_state"))
}

// ---- gripper and hand (dimensionless 0..1000 scales) ----

fn gripper(obj: Obj) -> Request {
    // Every gripper motion is acknowledged with the generic name `set_gripper`.
    obj.flag(Tag::Command("set_gripper"), "state")
}

/// `set_gripper_route`: opening range 0..=1000.
pub fn set_gripper_route(min: u16, max: u16) -> Result<Request, EncodeError> {
    let min = ranged("min", min as i64, 0, 1000)?;
    let max = ranged("max", max as i64, min, 1000)?;
    Ok(Obj::new("set_gripper_route")
        .field("min", &min)
        .field("max", &max)
        .echo("state"))
}

/// `set_gripper_position`: opening 1..=1000.
pub fn set_gripper_position(position: u16, block: bool) -> Result<Request, EncodeError> {
    let p = ranged("position", position as i64, 1, 1000)?;
    Ok(gripper(
        Obj::new("set_gripper_position")
            .field("position", &p)
            .field("block", &block),
    ))
}

fn pick(
    command: &'static str,
    speed: u16,
    force: u16,
    block: bool,
) -> Result<Request, EncodeError> {
    let s = ranged("speed", speed as i64, 1, 1000)?;
    let f = ranged("force", force as i64, 50, 1000)?;
    Ok(gripper(
        Obj::new(command)
            .field("speed", &s)
            .field("force", &f)
            .field("block", &block),
    ))
}

/// `set_gripper_pick`: close with speed 1..=1000 until force 50..=1000 is reached.
pub fn set_gripper_pick(speed: u16, force: u16, block: bool) -> Result<Request, EncodeError> {
    pick("set_gripper_pick", speed, force, block)
}

/// `set_gripper_pick_on`: continuous force grip.
pub fn set_gripper_pick_on(speed: u16, force: u16, block: bool) -> Result<Request, EncodeError> {
    pick("set_gripper_pick_on", speed, force, block)
}

/// `set_gripper_release`: open with speed 1..=1000.
pub fn set_gripper_release(speed: u16, block: bool) -> Result<Request, EncodeError> {
    let s = ranged("speed", speed as i64, 1, 1000)?;
    Ok(gripper(
        Obj::new("set_gripper_release")
            .field("speed", &s)
            .field("block", &block),
    ))
}

/// `set_hand_posture`: preset 1..=40.
pub fn set_hand_posture(posture: u8, block: bool) -> Result<Request, EncodeError> {
    let n = ranged("posture_num", posture as i64, 1, 40)?;
    Ok(Obj::new("set_hand_posture")
        .field("posture_num", &n)
        .field("block", &block)
        .echo("set_state"))
}

/// `set_hand_seq`: sequence 1..=40.
pub fn set_hand_seq(seq: u8, block: bool) -> Result<Request, EncodeError> {
    let n = ranged("seq_num", seq as i64, 1, 40)?;
    Ok(Obj::new("set_hand_seq")
        .field("seq_num", &n)
        .field("block", &block)
        .echo("set_state"))
}

/// `set_hand_angle`: six finger values 0..=1000, `None` keeps the current one (-1).
pub fn set_hand_angle(angles: [Option<u16>; 6], block: bool) -> Result<Request, EncodeError> {
    let v = angles
        .iter()
        .map(|a| match a {
            Some(a) => ranged("hand_angle", *a as i64, 0, 1000),
            None => Ok(-1),
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Obj::new("set_hand_angle")
        .field("hand_angle", &v)
        .field("block", &block)
        .echo("set_state"))
}

/// `set_hand_speed` 1..=1000.
pub fn set_hand_speed(speed: u16) -> Result<Request, EncodeError> {
    let s = ranged("hand_speed", speed as i64, 1, 1000)?;
    Ok(Obj::new("set_hand_speed")
        .field("hand_speed", &s)
        .echo("set_state"))
}

/// `set_hand_force` 1..=1000.
pub fn set_hand_force(force: u16) -> Result<Request, EncodeError> {
    let f = ranged("hand_force", force as i64, 1, 1000)?;
    Ok(Obj::new("set_hand_force")
        .field("hand_force", &f)
        .echo("set_state"))
}

// ---- realtime push ----

/// Optional data in the realtime push; `None` leaves the controller's setting unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct PushCustom {
    /// Joint speeds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_speed: Option<bool>,
    /// Lift state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lift_state: Option<bool>,
    /// Expansion joint state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expand_state: Option<bool>,
    /// The `arm_current_status` string.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_current_status: Option<bool>,
    /// Aloha handle switches.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aloha_state: Option<bool>,
}

/// What `set_realtime_push` sends.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PushSettings {
    /// Period in milliseconds, a positive multiple of 5.
    pub period_ms: u32,
    /// Push on or off.
    pub enable: bool,
    /// Target UDP port.
    pub port: u16,
    /// Target IPv4 address (dotted).
    pub ip: std::net::Ipv4Addr,
    /// Force data frame (0 sensor, 1 work, 2 tool); omit for arms without a force sensor.
    pub force_coordinate: Option<u8>,
    /// Optional data.
    pub custom: PushCustom,
}

/// `set_realtime_push`; the reply's result key is `state`.
pub fn set_realtime_push(s: &PushSettings) -> Result<Request, EncodeError> {
    if s.period_ms == 0 || !s.period_ms.is_multiple_of(5) {
        return Err(EncodeError::OutOfRange {
            field: "period_ms (multiple of 5)",
            value: s.period_ms as i64,
            min: 5,
            max: 500_000,
        });
    }
    if s.port == 0 {
        return Err(EncodeError::OutOfRange {
            field: "port",
            value: 0,
            min: 1,
            max: 65535,
        });
    }
    let mut obj = Obj::new("set_realtime_push")
        .field("cycle", &(s.period_ms / 5))
        .field("enable", &s.enable)
        .field("port", &s.port);
    if let Some(f) = s.force_coordinate {
        obj = obj.field(
            "force_coordinate",
            &ranged("force_coordinate", f as i64, 0, 2)?,
        );
    }
    Ok(obj
        .field("ip", &s.ip.to_string())
        .field("custom", &s.custom)
        .echo("state"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compact_crlf_and_tags() {
        let r = movej(&[0.0; 6], MoveOpts::speed(20)).unwrap();
        assert_eq!(
            r.wire,
            "{\"command\":\"movej\",\"joint\":[0,0,0,0,0,0],\"v\":20,\"r\":0,\"trajectory_connect\":0}\r\n"
        );
        assert_eq!(
            r.expect,
            Expect::Flag {
                tag: Tag::Command("movej"),
                key: Some("receive_state")
            }
        );
        assert_eq!(
            get_dh_data().expect.tag(),
            Some(Tag::Command("get_DH_data"))
        );
    }

    #[test]
    fn refuses_bad_arguments() {
        assert!(matches!(
            movej(&[0.0; 8], MoveOpts::speed(20)),
            Err(EncodeError::JointCount { got: 8 })
        ));
        assert!(movej(&[0.0; 6], MoveOpts::speed(0)).is_err());
        assert!(movej(&[f64::NAN; 6], MoveOpts::speed(10)).is_err());
        assert!(set_collision_stage(9).is_err());
        assert!(set_gripper_position(0, true).is_err());
        assert!(set_arm_max_line_speed(0.0).is_err());
        assert!(set_joint_step(0, 0.1, 10).is_err());
    }
}
