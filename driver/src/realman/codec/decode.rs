//! Typed decoders for reply bodies (docs/protocols/realman.md §3–§11). Each takes the reply
//! object and returns SI values; a missing or mistyped field is a [`DecodeError`].

use std::collections::BTreeMap;

use serde_json::{Map, Value};

use super::request::DhRow;
use super::types::{controller_errors, ControllerError, JointErrorFlags, Pose, TrajectoryKind};
use super::units::{mdeg_to_rad, micro_amp_to_a, milli, milli_rpm_to_rad_s, um_to_m};
use super::DecodeError;

/// A reply object.
pub type Body = Map<String, Value>;

pub(crate) fn int(body: &Body, key: &'static str) -> Result<i64, DecodeError> {
    body.get(key)
        .and_then(Value::as_i64)
        .ok_or(DecodeError::Field(key))
}

pub(crate) fn boolean(body: &Body, key: &'static str) -> Result<bool, DecodeError> {
    body.get(key)
        .and_then(Value::as_bool)
        .ok_or(DecodeError::Field(key))
}

fn string(body: &Body, key: &'static str) -> Result<String, DecodeError> {
    body.get(key)
        .and_then(Value::as_str)
        .map(str::to_string)
        .ok_or(DecodeError::Field(key))
}

pub(crate) fn object<'a>(body: &'a Body, key: &'static str) -> Result<&'a Body, DecodeError> {
    body.get(key)
        .and_then(Value::as_object)
        .ok_or(DecodeError::Field(key))
}

pub(crate) fn ints(body: &Body, key: &'static str) -> Result<Vec<i64>, DecodeError> {
    body.get(key)
        .and_then(Value::as_array)
        .and_then(|a| a.iter().map(Value::as_i64).collect::<Option<Vec<_>>>())
        .ok_or(DecodeError::Field(key))
}

fn fixed<const N: usize>(body: &Body, key: &'static str) -> Result<[i64; N], DecodeError> {
    ints(body, key)?
        .try_into()
        .map_err(|_| DecodeError::Field(key))
}

fn map(v: Vec<i64>, f: fn(i64) -> f64) -> Vec<f64> {
    v.into_iter().map(f).collect()
}

/// Interprets the boolean result `key` of a setter reply: `Ok(true)` accepted, `Ok(false)` refused.
/// With `key == None` (undocumented key) the first boolean other than the tag is used.
pub fn result_flag(body: &Body, key: Option<&'static str>) -> Result<bool, DecodeError> {
    match key {
        Some(k) => boolean(body, k),
        None => body
            .iter()
            .find_map(|(_, v)| v.as_bool())
            .ok_or(DecodeError::Field("result flag")),
    }
}

/// `[x, y, z (0.001 mm), rx, ry, rz (0.001 rad)]` to a [`Pose`].
pub fn pose(body: &Body, key: &'static str) -> Result<Pose, DecodeError> {
    let p: [i64; 6] = fixed(body, key)?;
    Ok(Pose {
        position_m: [um_to_m(p[0]), um_to_m(p[1]), um_to_m(p[2])],
        euler_rad: [milli(p[3]), milli(p[4]), milli(p[5])],
    })
}

/// Joint angles in 0.001° under `key`, as radians.
pub fn joints_rad(body: &Body, key: &'static str) -> Result<Vec<f64>, DecodeError> {
    Ok(map(ints(body, key)?, mdeg_to_rad))
}

/// Product identification from `get_arm_software_info`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SoftwareInfo {
    /// `Product_version`, e.g. `RM65-B`.
    pub product_version: String,
    /// Model prefix recognised in it (`RM65`, `RM75`, …), if any.
    pub model: Option<&'static str>,
    /// Degrees of freedom of that model (6 when unknown).
    pub dof: usize,
    /// Controller generation: 4 when `robot_controller_version` is present, else 3.
    pub generation: u8,
    /// `ctrl_info.version`, when present.
    pub controller_version: Option<String>,
    /// `plan_info.version`, when present.
    pub planner_version: Option<String>,
    /// `algorithm_info.version`, when present.
    pub algorithm_version: Option<String>,
}

/// Model prefixes the vendor SDK recognises, longest first so `RML63III` wins over `RML63`.
const MODELS: [(&str, usize); 16] = [
    ("RML63III", 6),
    ("RXL75II", 7),
    ("RXR75II", 7),
    ("ZPFL73", 7),
    ("ZPFR73", 7),
    ("ZPFL74", 7),
    ("ZPFR74", 7),
    ("RML63", 6),
    ("ECO65", 6),
    ("ECO62", 6),
    ("ECO63", 6),
    ("GEN72", 7),
    ("RXL75", 7),
    ("RXR75", 7),
    ("RM65", 6),
    ("RM75", 7),
];

fn nested_version(body: &Body, key: &'static str) -> Option<String> {
    body.get(key)?.get("version")?.as_str().map(str::to_string)
}

/// Decodes `get_arm_software_info`.
pub fn software_info(body: &Body) -> Result<SoftwareInfo, DecodeError> {
    let product_version = string(body, "Product_version")?;
    let found = MODELS.iter().find(|(p, _)| product_version.starts_with(p));
    Ok(SoftwareInfo {
        model: found.map(|(p, _)| *p),
        dof: found.map_or(6, |(_, d)| *d),
        generation: if body.contains_key("robot_controller_version") {
            4
        } else {
            3
        },
        controller_version: nested_version(body, "ctrl_info"),
        planner_version: nested_version(body, "plan_info"),
        algorithm_version: nested_version(body, "algorithm_info"),
        product_version,
    })
}

/// What `get_arm_current_trajectory` reports.
#[derive(Debug, Clone, PartialEq)]
pub struct CurrentTrajectory {
    /// Kind of motion under way (`None` at rest).
    pub kind: TrajectoryKind,
    /// Joint angles (rad) for `none`/`movej`, else empty.
    pub joints_rad: Vec<f64>,
    /// Tool pose for Cartesian kinds.
    pub pose: Option<Pose>,
}

/// Decodes `get_arm_current_trajectory`.
pub fn current_trajectory(body: &Body) -> Result<CurrentTrajectory, DecodeError> {
    let kind = TrajectoryKind::from_wire(&string(body, "type")?);
    let data = ints(body, "data")?;
    let cartesian = matches!(
        kind,
        TrajectoryKind::MoveL | TrajectoryKind::MoveC | TrajectoryKind::MoveS
    );
    if cartesian {
        let p: [i64; 6] = data.try_into().map_err(|_| DecodeError::Field("data"))?;
        let pose = Pose {
            position_m: [um_to_m(p[0]), um_to_m(p[1]), um_to_m(p[2])],
            euler_rad: [milli(p[3]), milli(p[4]), milli(p[5])],
        };
        return Ok(CurrentTrajectory {
            kind,
            joints_rad: Vec::new(),
            pose: Some(pose),
        });
    }
    Ok(CurrentTrajectory {
        kind,
        joints_rad: map(data, mdeg_to_rad),
        pose: None,
    })
}

/// The realtime push configuration (`get_realtime_push`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PushConfig {
    /// Period in milliseconds (`cycle` × 5).
    pub period_ms: u32,
    /// Push enabled.
    pub enable: bool,
    /// Target UDP port.
    pub port: u16,
    /// Force data frame (-1: no force sensor).
    pub force_coordinate: i64,
    /// Target address as sent by the controller.
    pub ip: String,
    /// Optional data flags.
    pub custom: BTreeMap<String, bool>,
}

/// Decodes `get_realtime_push`.
pub fn push_config(body: &Body) -> Result<PushConfig, DecodeError> {
    let cycle = int(body, "cycle")?;
    let port = int(body, "port")?;
    let custom = match body.get("custom") {
        Some(Value::Object(m)) => m
            .iter()
            .filter_map(|(k, v)| v.as_bool().map(|b| (k.clone(), b)))
            .collect(),
        _ => BTreeMap::new(),
    };
    Ok(PushConfig {
        period_ms: cycle
            .checked_mul(5)
            .and_then(|ms| u32::try_from(ms).ok())
            .ok_or(DecodeError::Field("cycle"))?,
        enable: boolean(body, "enable")?,
        port: u16::try_from(port).map_err(|_| DecodeError::Field("port"))?,
        force_coordinate: body
            .get("force_coordinate")
            .and_then(Value::as_i64)
            .unwrap_or(-1),
        ip: string(body, "ip").unwrap_or_default(),
        custom,
    })
}

/// A named frame (`get_current_work_frame`).
#[derive(Debug, Clone, PartialEq)]
pub struct WorkFrame {
    /// Frame name.
    pub name: String,
    /// Pose of the frame in the base.
    pub pose: Pose,
}

/// Decodes `get_current_work_frame`.
pub fn work_frame(body: &Body) -> Result<WorkFrame, DecodeError> {
    Ok(WorkFrame {
        name: string(body, "frame_name")?,
        pose: pose(body, "pose")?,
    })
}

/// The tool frame (`get_current_tool_frame`).
#[derive(Debug, Clone, PartialEq)]
pub struct ToolFrame {
    /// Tool name.
    pub name: String,
    /// Pose of the tool in the flange.
    pub pose: Pose,
    /// Payload mass in kg.
    pub payload_kg: f64,
    /// Payload centre of mass in the flange, metres.
    pub com_m: [f64; 3],
}

/// Decodes `get_current_tool_frame`.
pub fn tool_frame(body: &Body) -> Result<ToolFrame, DecodeError> {
    let c: [i64; 3] = fixed(body, "position")?;
    Ok(ToolFrame {
        name: string(body, "tool_name")?,
        pose: pose(body, "pose")?,
        payload_kg: milli(int(body, "payload")?),
        // 0.001 mm.
        com_m: [um_to_m(c[0]), um_to_m(c[1]), um_to_m(c[2])],
    })
}

/// Decodes `get_install_pose`: rotation, pitch, azimuth in radians.
pub fn install_pose(body: &Body) -> Result<[f64; 3], DecodeError> {
    let p: [i64; 3] = fixed(body, "pose")?;
    Ok(p.map(|d| (d as f64).to_radians()))
}

/// Joint angle limits (`min_pos` / `max_pos`) in radians.
pub fn joint_limits(body: &Body, key: &'static str) -> Result<Vec<f64>, DecodeError> {
    joints_rad(body, key)
}

/// Joint speed (`joint_speed`, rad/s) or acceleration (`joint_acc`, rad/s²) limits.
pub fn joint_rates(body: &Body, key: &'static str) -> Result<Vec<f64>, DecodeError> {
    Ok(map(ints(body, key)?, milli_rpm_to_rad_s))
}

/// Decodes `get_DH_data` (`joint_1`…`joint_7`).
pub fn dh_table(body: &Body) -> Result<Vec<DhRow>, DecodeError> {
    const KEYS: [&str; 7] = [
        "joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6", "joint_7",
    ];
    let mut rows = Vec::new();
    for key in KEYS.iter().take_while(|k| body.contains_key(**k)) {
        let r: [i64; 4] = fixed(body, key)?;
        rows.push(DhRow {
            alpha_rad: mdeg_to_rad(r[0]),
            a_m: um_to_m(r[1]),
            d_m: um_to_m(r[2]),
            offset_rad: mdeg_to_rad(r[3]),
        });
    }
    if rows.len() < 6 {
        return Err(DecodeError::Field("joint_6"));
    }
    Ok(rows)
}

/// Errors either as the `err` array (firmware ≥ 1.6.7) or as `arm_err`/`sys_err`.
pub fn errors(body: &Body) -> Result<Vec<ControllerError>, DecodeError> {
    if body.contains_key("err") {
        let codes = ints(body, "err")?;
        return Ok(controller_errors(codes.into_iter().map(|c| c as u32)));
    }
    let mut codes = Vec::new();
    for key in ["arm_err", "sys_err"] {
        if let Some(v) = body.get(key) {
            codes.push(v.as_i64().ok_or(DecodeError::Field(key))? as u32);
        }
    }
    Ok(controller_errors(codes))
}

/// `get_current_arm_state`.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmSnapshot {
    /// Joint angles, rad.
    pub joints_rad: Vec<f64>,
    /// Tool pose in the work frame.
    pub pose: Pose,
    /// Active errors (empty = none).
    pub errors: Vec<ControllerError>,
}

/// Decodes `get_current_arm_state` in both error forms.
pub fn arm_snapshot(body: &Body) -> Result<ArmSnapshot, DecodeError> {
    let s = object(body, "arm_state")?;
    Ok(ArmSnapshot {
        joints_rad: joints_rad(s, "joint")?,
        pose: pose(s, "pose")?,
        errors: errors(s)?,
    })
}

/// `get_arm_all_state`.
#[derive(Debug, Clone, PartialEq)]
pub struct AllState {
    /// Joint temperatures, °C.
    pub temperatures_c: Vec<f64>,
    /// Joint currents, A.
    pub currents_a: Vec<f64>,
    /// Joint voltages, V.
    pub voltages_v: Vec<f64>,
    /// Joint error bits.
    pub joint_errors: Vec<JointErrorFlags>,
    /// Joint enable flags.
    pub enabled: Vec<bool>,
    /// Controller errors.
    pub errors: Vec<ControllerError>,
}

fn flags(v: Vec<i64>) -> Vec<JointErrorFlags> {
    v.into_iter().map(|f| JointErrorFlags(f as u16)).collect()
}

/// Decodes `get_arm_all_state`.
pub fn all_state(body: &Body) -> Result<AllState, DecodeError> {
    let s = object(body, "all_state")?;
    Ok(AllState {
        temperatures_c: map(ints(s, "temperature")?, milli),
        currents_a: map(ints(s, "current")?, micro_amp_to_a),
        voltages_v: map(ints(s, "voltage")?, milli),
        joint_errors: flags(ints(s, "err_flag")?),
        enabled: ints(s, "en_flag")?.into_iter().map(|e| e != 0).collect(),
        errors: errors(s)?,
    })
}

/// `get_joint_err_flag`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JointFlags {
    /// Error bits per joint.
    pub errors: Vec<JointErrorFlags>,
    /// True when the joint's brake is engaged (wire 1 = not released).
    pub brake_engaged: Vec<bool>,
}

/// Decodes `get_joint_err_flag`.
pub fn joint_flags(body: &Body) -> Result<JointFlags, DecodeError> {
    Ok(JointFlags {
        errors: flags(ints(body, "err_flag")?),
        brake_engaged: ints(body, "brake_state")?
            .into_iter()
            .map(|b| b != 0)
            .collect(),
    })
}

/// `get_controller_state`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerState {
    /// Supply voltage, V.
    pub voltage_v: f64,
    /// Supply current, A (wire 0.001 A).
    pub current_a: f64,
    /// Temperature, °C.
    pub temperature_c: f64,
    /// Error code (0 = none).
    pub error: Option<ControllerError>,
}

/// Decodes `get_controller_state`.
pub fn controller_state(body: &Body) -> Result<ControllerState, DecodeError> {
    let e = int(body, "err_flag")? as u32;
    Ok(ControllerState {
        voltage_v: milli(int(body, "voltage")?),
        current_a: milli(int(body, "current")?),
        temperature_c: milli(int(body, "temperature")?),
        error: (e != 0).then(|| ControllerError::from_code(e)),
    })
}

/// `get_current_joint_temperature` (°C), `_current` (A) or `_voltage` (V).
pub fn joint_measure(body: &Body, key: &'static str) -> Result<Vec<f64>, DecodeError> {
    let f = if key == "joint_current" {
        micro_amp_to_a
    } else {
        milli
    };
    Ok(map(ints(body, key)?, f))
}

/// A thousandths scalar (`arm_line_speed` 0.001 m/s etc.) in SI.
pub fn milli_scalar(body: &Body, key: &'static str) -> Result<f64, DecodeError> {
    Ok(milli(int(body, key)?))
}

/// `get_gripper_state`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GripperState {
    /// Enabled.
    pub enabled: bool,
    /// Online.
    pub online: bool,
    /// Error bits (bit0 stall, bit1 over-temp, bit2 over-current, bit3 driver, bit4 comms).
    pub error: u16,
    /// Mode.
    pub mode: GripperMode,
    /// Force, grams.
    pub force_g: i64,
    /// Temperature, °C.
    pub temperature_c: i64,
    /// Opening, 0..=1000.
    pub position: i64,
}

/// Gripper `mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GripperMode {
    /// 1: fully open, idle.
    OpenIdle,
    /// 2: fully closed, idle.
    ClosedIdle,
    /// 3: stopped, idle.
    StoppedIdle,
    /// 4: closing.
    Closing,
    /// 5: opening.
    Opening,
    /// 6: stopped by force while closing.
    ForceStopped,
    /// Another value.
    Unknown(i64),
}

/// Decodes `get_gripper_state`.
pub fn gripper_state(body: &Body) -> Result<GripperState, DecodeError> {
    let mode = match int(body, "mode")? {
        1 => GripperMode::OpenIdle,
        2 => GripperMode::ClosedIdle,
        3 => GripperMode::StoppedIdle,
        4 => GripperMode::Closing,
        5 => GripperMode::Opening,
        6 => GripperMode::ForceStopped,
        m => GripperMode::Unknown(m),
    };
    Ok(GripperState {
        enabled: int(body, "enable")? != 0,
        online: int(body, "status")? != 0,
        error: int(body, "error")? as u16,
        mode,
        force_g: int(body, "current_force")?,
        temperature_c: int(body, "temperature")?,
        position: int(body, "actpos")?,
    })
}

/// Decodes `get_arm_power_state`: true when the arm is powered.
pub fn power_state(body: &Body) -> Result<bool, DecodeError> {
    Ok(int(body, "power_state")? != 0)
}

/// Decodes `get_collision_stage` (0..=8).
pub fn collision_stage(body: &Body) -> Result<u8, DecodeError> {
    u8::try_from(int(body, "collision_stage")?).map_err(|_| DecodeError::Field("collision_stage"))
}

/// Decodes `get_self_collision_enable`.
pub fn self_collision(body: &Body) -> Result<bool, DecodeError> {
    boolean(body, "enable_state")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(text: &str) -> Body {
        serde_json::from_str(text).unwrap()
    }

    #[test]
    fn hostile_numbers_are_errors_not_panics() {
        let huge = body(
            r#"{"command":"get_realtime_push","cycle":9223372036854775807,"enable":true,"port":8089}"#,
        );
        assert_eq!(push_config(&huge), Err(DecodeError::Field("cycle")));
        let port = body(r#"{"command":"get_realtime_push","cycle":1,"enable":true,"port":70000}"#);
        assert_eq!(push_config(&port), Err(DecodeError::Field("port")));
        let stage = body(r#"{"state":"get_collision_stage","collision_stage":-1}"#);
        assert_eq!(
            collision_stage(&stage),
            Err(DecodeError::Field("collision_stage"))
        );
        let short = body(
            r#"{"state":"current_arm_state","arm_state":{"joint":[0],"pose":[1,2],"err":[]}}"#,
        );
        assert_eq!(arm_snapshot(&short), Err(DecodeError::Field("pose")));
    }

    #[test]
    fn software_info_models() {
        let b = body(
            r#"{"command":"arm_software_info","Product_version":"RML63III-6F","robot_controller_version":"4.0"}"#,
        );
        let s = software_info(&b).unwrap();
        assert_eq!((s.model, s.dof, s.generation), (Some("RML63III"), 6, 4));
        let b = body(r#"{"command":"arm_software_info","Product_version":"GEN72-B"}"#);
        assert_eq!(software_info(&b).unwrap().dof, 7);
        let b = body(r#"{"command":"arm_software_info","Product_version":"XYZ"}"#);
        assert_eq!(software_info(&b).unwrap().model, None);
    }
}
