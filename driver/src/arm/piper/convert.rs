//! Piper driver values and errors in the Arm API's terms.

use std::time::SystemTime;

use crate::arm::error::{AbcErrorCode, ArmError};
use crate::arm::kinematics::{Chain, MdhJoint};
use crate::arm::types::{
    ArmCurrentStatus, ArmForceSensor, ArmRealtimeState, GripperState, JointState, Pose,
};
use crate::piper::{
    self as pp, ArmStatusCode, ClientLimits, DhVariant, MotionStatus, PiperError, PiperState,
};

const RAD_S_TO_RPM: f64 = 60.0 / (2.0 * std::f64::consts::PI);

/// The code for each driver error. A target outside the client-side limits is
/// `PARAM_OUT_OF_RANGE`; a bus failure `ARM_DATA_SEND_FAILED`; no confirmation in time
/// `ARM_TIMEOUT`; a refused acknowledgement `ARM_CTRL_FALSE`.
pub(crate) fn error(e: PiperError) -> ArmError {
    let code = match &e {
        PiperError::Bus { .. } => AbcErrorCode::ArmDataSendFailed,
        PiperError::Timeout { .. } | PiperError::EnableTimeout { .. } => AbcErrorCode::ArmTimeout,
        PiperError::Rejected { .. } => AbcErrorCode::ArmCtrlFalse,
        PiperError::OutOfLimit { .. } | PiperError::InvalidValue { .. } => {
            AbcErrorCode::ParamOutOfRange
        }
        PiperError::InvalidJoint { .. } => AbcErrorCode::InvalidArgument,
        PiperError::AlreadyOwned { .. } => AbcErrorCode::InvalidState,
        PiperError::Disconnected => AbcErrorCode::ArmDataReceiveFailed,
        PiperError::Decode { .. } => AbcErrorCode::ArmReturnDataErr,
        PiperError::Unsupported { .. } => AbcErrorCode::NotImplemented,
    };
    ArmError::caused_by(code, e)
}

/// The code an arm status reports as an error, if it is one: no IK solution, a singularity
/// and a target beyond a joint limit are `ARM_OUT_OF_RANGE` (as an unreachable pose is on
/// every vendor); the other faults are `ARM_ERROR`.
pub(crate) fn status_error(code: ArmStatusCode) -> Option<AbcErrorCode> {
    match code {
        ArmStatusCode::Normal
        | ArmStatusCode::TeachRecord
        | ArmStatusCode::TeachExecute
        | ArmStatusCode::TeachPause => None,
        ArmStatusCode::NoIkSolution
        | ArmStatusCode::Singularity
        | ArmStatusCode::TargetAngleOverLimit => Some(AbcErrorCode::ArmOutOfRange),
        _ => Some(AbcErrorCode::ArmError),
    }
}

/// The Piper's kinematic chain (the driver's DH table, the SDK's joint limits).
pub(crate) fn chain(variant: DhVariant) -> Chain {
    let limits = ClientLimits::default().joints_rad;
    Chain::new(
        pp::dh_table(variant)
            .iter()
            .zip(limits)
            .map(|(row, (min_rad, max_rad))| MdhJoint {
                min_rad,
                max_rad,
                ..*row
            })
            .collect(),
    )
}

pub(crate) fn pose_to_pp(p: &Pose) -> pp::Pose {
    pp::Pose {
        position_m: p.position_m,
        orientation_rad: p.euler_rad,
    }
}

/// Gripper feedback in the API's terms. The Piper reports jaw opening and torque, not force,
/// temperature or motion mode: `current_force` carries the torque in mN·m, `temperature` is
/// 0, and `mode` is 1/2 at the ends of the stroke and 3 in between.
pub(crate) fn gripper(g: &pp::GripperState, max_stroke_m: f64) -> GripperState {
    let s = g.status;
    let mut error = 0;
    if s.motor_over_temp() || s.driver_over_temp() {
        error |= 1 << 1;
    }
    if s.over_current() {
        error |= 1 << 2;
    }
    if s.driver_error() || s.under_voltage() || s.sensor_fault() {
        error |= 1 << 3;
    }
    let actpos = ((g.stroke_m / max_stroke_m) * 1000.0)
        .round()
        .clamp(0.0, 1000.0) as i32;
    GripperState {
        status: if s.enabled() { 1 } else { -1 },
        error,
        mode: match actpos {
            990.. => 1,
            ..=10 => 2,
            _ => 3,
        },
        current_force: (g.torque_nm * 1000.0).round() as i32,
        temperature: 0,
        actpos,
    }
}

fn arm_status(s: &PiperState) -> ArmCurrentStatus {
    let Some(a) = &s.arm_status else {
        return ArmCurrentStatus::Unknown;
    };
    let a = a.value;
    if a.status == ArmStatusCode::EmergencyStop {
        return ArmCurrentStatus::Stopped;
    }
    if status_error(a.status).is_some() {
        return ArmCurrentStatus::Error;
    }
    match a.motion {
        MotionStatus::Reached => ArmCurrentStatus::Idle,
        _ => ArmCurrentStatus::Moving,
    }
}

/// One feedback cycle in the API's units; `None` before the first joint feedback.
pub(crate) fn realtime(
    name: &str,
    since_connect: std::time::Duration,
    s: &PiperState,
    max_stroke_m: f64,
) -> Option<ArmRealtimeState> {
    let joints = s.joints_rad()?;
    let high = |f: fn(&pp::MotorState) -> f64| -> Vec<f64> {
        s.high_speed
            .iter()
            .map(|m| m.as_ref().map_or(0.0, |m| f(&m.value)))
            .collect()
    };
    let low = |f: fn(&pp::DriverState) -> f64| -> Vec<f64> {
        s.low_speed
            .iter()
            .map(|m| m.as_ref().map_or(0.0, |m| f(&m.value)))
            .collect()
    };
    Some(ArmRealtimeState {
        name: name.to_string(),
        timestamp: SystemTime::now(),
        since_connect,
        joint_status: JointState {
            joint_position: joints.iter().map(|r| r.to_degrees()).collect(),
            joint_speed: high(|m| m.speed_rad_s * RAD_S_TO_RPM),
            joint_current: high(|m| m.current_a * 1000.0),
            joint_temperature: low(|d| d.motor_temp_c),
            joint_voltage: low(|d| d.bus_voltage_v),
            joint_err_code: s
                .low_speed
                .iter()
                .map(|d| {
                    d.as_ref()
                        .map_or(0, |d| u32::from(d.value.status.0 & !(1 << 6)))
                })
                .collect(),
            joint_en_flag: s
                .low_speed
                .iter()
                .map(|d| d.as_ref().is_some_and(|d| d.value.status.enabled()))
                .collect(),
        },
        force_sensor: ArmForceSensor::default(),
        arm_current_status: arm_status(s),
        gripper_state: s.gripper.as_ref().map(|g| gripper(&g.value, max_stroke_m)),
        ee_pose: s.end_pose.as_ref().map_or_else(Pose::default, |p| {
            Pose::new(p.value.position_m, p.value.orientation_rad)
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::types::IkMode;

    #[test]
    fn the_chain_agrees_with_the_driver_forward_kinematics() {
        for variant in [DhVariant::Offset, DhVariant::Legacy] {
            let chain = chain(variant);
            for q in [[0.0; 6], [0.3, 0.6, -0.5, 0.2, -0.3, 0.4]] {
                let flange = pp::forward_kinematics(q, variant)[5];
                let p = chain.forward(&q);
                let want = [flange.x_mm, flange.y_mm, flange.z_mm].map(|v| v / 1000.0);
                let want_rpy =
                    [flange.roll_deg, flange.pitch_deg, flange.yaw_deg].map(f64::to_radians);
                for i in 0..3 {
                    assert!(
                        (p.position_m[i] - want[i]).abs() < 1e-9,
                        "{variant:?} {p:?}"
                    );
                    assert!(
                        (p.euler_rad[i] - want_rpy[i]).abs() < 1e-9,
                        "{variant:?} {p:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn ik_round_trips_inside_the_sdk_limits() {
        let chain = chain(DhVariant::Offset);
        let q = [0.3, 0.6, -0.5, 0.2, -0.3, 0.4];
        let target = chain.forward(&q);
        let sol = chain
            .inverse(
                &target,
                &[0.0, 0.5, -0.4, 0.0, 0.0, 0.0],
                IkMode::IterativeSearch,
            )
            .expect("solution");
        let (dp, dr) = crate::arm::kinematics::pose_distance(&chain.forward(&sol), &target);
        assert!(dp < 1e-5 && dr < 1e-5, "{dp} {dr}");
        assert!(chain.within_limits(&sol));
    }

    #[test]
    fn driver_errors_map_to_their_codes() {
        let timeout = PiperError::Timeout {
            what: "x",
            waited: std::time::Duration::from_millis(1),
        };
        assert_eq!(error(timeout).code, AbcErrorCode::ArmTimeout);
        assert_eq!(
            error(PiperError::Disconnected).code,
            AbcErrorCode::ArmDataReceiveFailed
        );
        assert_eq!(
            status_error(ArmStatusCode::NoIkSolution),
            Some(AbcErrorCode::ArmOutOfRange)
        );
        assert_eq!(status_error(ArmStatusCode::Normal), None);
        assert_eq!(
            status_error(ArmStatusCode::Collision),
            Some(AbcErrorCode::ArmError)
        );
    }
}
