//! The UDP realtime push datagram (`realtime_arm_joint_state`, docs/protocols/realman.md §11).

use serde_json::Value;

use super::decode::{errors, ints, object, Body};
use super::types::{ArmStatus, ControllerError, JointErrorFlags, Pose};
use super::units::{mdeg_to_rad, micro_amp_to_a, milli, um_to_m};
use super::DecodeError;

/// The unit of `joint_speed` in the push; sources disagree (docs §11, §15), so it is configurable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JointSpeedUnit {
    /// 0.01 °/s (the vendor SDK's reading; the default).
    #[default]
    CentiDegPerSecond,
    /// 0.01 RPM (protocol doc v3.7.4).
    CentiRpm,
    /// 0.02 RPM (newer protocol doc).
    FiftiethRpm,
}

impl JointSpeedUnit {
    fn to_rad_s(self, v: i64) -> f64 {
        let rpm_to_rad_s = 2.0 * std::f64::consts::PI / 60.0;
        match self {
            Self::CentiDegPerSecond => (v as f64 * 0.01).to_radians(),
            Self::CentiRpm => v as f64 * 0.01 * rpm_to_rad_s,
            Self::FiftiethRpm => v as f64 * 0.02 * rpm_to_rad_s,
        }
    }
}

/// One decoded realtime state sample.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmState {
    /// Joint positions, rad.
    pub joints_rad: Vec<f64>,
    /// Joint speeds, rad/s (only when the push includes them).
    pub joint_speeds_rad_s: Option<Vec<f64>>,
    /// Joint currents, A.
    pub currents_a: Vec<f64>,
    /// Joint temperatures, °C.
    pub temperatures_c: Vec<f64>,
    /// Joint voltages, V.
    pub voltages_v: Vec<f64>,
    /// Joint enable flags.
    pub enabled: Vec<bool>,
    /// Joint error bits.
    pub joint_errors: Vec<JointErrorFlags>,
    /// Tool pose.
    pub pose: Pose,
    /// Tool orientation as a quaternion (w, x, y, z).
    pub quaternion_wxyz: [f64; 4],
    /// Controller errors (empty = none).
    pub errors: Vec<ControllerError>,
    /// Motion status (only when the push includes it).
    pub status: Option<ArmStatus>,
}

fn triple(body: &Body, key: &'static str, f: fn(i64) -> f64) -> Result<[f64; 3], DecodeError> {
    let v: [i64; 3] = ints(body, key)?
        .try_into()
        .map_err(|_| DecodeError::Field(key))?;
    Ok(v.map(f))
}

/// Decodes one datagram (trailing whitespace or CRLF allowed).
pub fn decode_push(datagram: &[u8], speed_unit: JointSpeedUnit) -> Result<ArmState, DecodeError> {
    let value: Value = serde_json::from_slice(datagram.trim_ascii())
        .map_err(|e| DecodeError::Json(e.to_string()))?;
    let Value::Object(body) = value else {
        return Err(DecodeError::NotAnObject);
    };
    match body.get("state").and_then(Value::as_str) {
        Some("realtime_arm_joint_state") => {}
        _ => return Err(DecodeError::NoTag),
    }
    let js = object(&body, "joint_status")?;
    let wp = object(&body, "waypoint")?;
    let q: [i64; 4] = ints(wp, "quat")?
        .try_into()
        .map_err(|_| DecodeError::Field("quat"))?;
    let speeds = match js.get("joint_speed") {
        None => None,
        Some(_) => Some(
            ints(js, "joint_speed")?
                .into_iter()
                .map(|v| speed_unit.to_rad_s(v))
                .collect(),
        ),
    };
    let status = match body.get("arm_current_status") {
        None => None,
        Some(v) => Some(ArmStatus::from_wire(
            v.as_str().ok_or(DecodeError::Field("arm_current_status"))?,
        )),
    };
    Ok(ArmState {
        joints_rad: ints(js, "joint_position")?
            .into_iter()
            .map(mdeg_to_rad)
            .collect(),
        joint_speeds_rad_s: speeds,
        currents_a: ints(js, "joint_current")?
            .into_iter()
            .map(micro_amp_to_a)
            .collect(),
        temperatures_c: ints(js, "joint_temperature")?
            .into_iter()
            .map(milli)
            .collect(),
        voltages_v: ints(js, "joint_voltage")?.into_iter().map(milli).collect(),
        enabled: ints(js, "joint_en_flag")?
            .into_iter()
            .map(|e| e != 0)
            .collect(),
        joint_errors: ints(js, "joint_err_code")?
            .into_iter()
            .map(|e| JointErrorFlags(e as u16))
            .collect(),
        pose: Pose {
            position_m: triple(wp, "position", um_to_m)?,
            euler_rad: triple(wp, "euler", milli)?,
        },
        quaternion_wxyz: q.map(|c| c as f64 * 1e-6),
        errors: errors(&body)?,
        status,
    })
}
