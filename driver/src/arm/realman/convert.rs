//! Realman driver values and errors in the Arm API's terms.

use std::time::SystemTime;

use crate::arm::error::{AbcErrorCode, ArmError};
use crate::arm::kinematics::{Chain, MdhJoint};
use crate::arm::types::{
    ArmCurrentStatus, ArmForceSensor, ArmRealtimeState, GripperState, JointState, Pose,
    TrajectoryMode,
};
use crate::realman::codec::EncodeError;
use crate::realman::{self as rm, ArmState, ArmStatus, GripperMode, RealmanError, Smoothing};

/// rad/s → RPM.
const RAD_S_TO_RPM: f64 = 60.0 / (2.0 * std::f64::consts::PI);

/// The code for each driver error: a `false` reply is the controller refusing
/// (`ARM_CTRL_FALSE`), a missing reply or arrival is `ARM_TIMEOUT`, a lost connection is
/// `ARM_DATA_RECEIVE_FAILED`, an unreadable reply `ARM_RETURN_DATA_ERR`, a failed motion
/// `ARM_ERROR`.
pub(crate) fn error(e: RealmanError) -> ArmError {
    let code = match &e {
        RealmanError::Connect { .. } | RealmanError::Io { .. } => AbcErrorCode::ArmDataSendFailed,
        RealmanError::Encode(EncodeError::OutOfRange { .. }) => AbcErrorCode::ParamOutOfRange,
        RealmanError::Encode(_) => AbcErrorCode::InvalidArgument,
        RealmanError::Timeout { .. } | RealmanError::MotionTimeout { .. } => {
            AbcErrorCode::ArmTimeout
        }
        RealmanError::Rejected { .. } => AbcErrorCode::ArmCtrlFalse,
        RealmanError::Malformed { .. } => AbcErrorCode::ArmReturnDataErr,
        RealmanError::MotionFailed { .. } => AbcErrorCode::ArmError,
        RealmanError::Disconnected { .. } => AbcErrorCode::ArmDataReceiveFailed,
        RealmanError::NoAddress => AbcErrorCode::InvalidState,
    };
    ArmError::caused_by(code, e)
}

pub(crate) fn pose_to_rm(p: &Pose) -> rm::Pose {
    rm::Pose {
        position_m: p.position_m,
        euler_rad: p.euler_rad,
    }
}

pub(crate) fn pose_from_rm(p: &rm::Pose) -> Pose {
    Pose::new(p.position_m, p.euler_rad)
}

pub(crate) fn smoothing(mode: TrajectoryMode) -> Smoothing {
    match mode {
        TrajectoryMode::Passthrough => Smoothing::Raw,
        TrajectoryMode::CurveFitting(k) => Smoothing::CurveFit(k),
        TrajectoryMode::Filtering(k) => Smoothing::Filter(k),
    }
}

/// The kinematic chain from the controller's DH table and joint limits, reporting the tool in
/// the work frame that were current at connect (as the controller's own poses are).
pub(crate) fn chain(h: &rm::Handshake) -> Chain {
    Chain::new(
        h.dh.iter()
            .enumerate()
            .map(|(i, row)| MdhJoint {
                a_m: row.a_m,
                alpha_rad: row.alpha_rad,
                d_m: row.d_m,
                offset_rad: row.offset_rad,
                min_rad: h
                    .joint_min_rad
                    .get(i)
                    .copied()
                    .unwrap_or(-std::f64::consts::PI),
                max_rad: h
                    .joint_max_rad
                    .get(i)
                    .copied()
                    .unwrap_or(std::f64::consts::PI),
            })
            .collect(),
    )
    .with_frames(
        &pose_from_rm(&h.work_frame.pose),
        &pose_from_rm(&h.tool_frame.pose),
    )
}

pub(crate) fn gripper(g: &rm::GripperState) -> GripperState {
    let mode = match g.mode {
        GripperMode::OpenIdle => 1,
        GripperMode::ClosedIdle => 2,
        GripperMode::StoppedIdle => 3,
        GripperMode::Closing => 4,
        GripperMode::Opening => 5,
        GripperMode::ForceStopped => 6,
        GripperMode::Unknown(v) => v as i32,
    };
    GripperState {
        status: match (g.online, g.enabled) {
            (false, _) => 0,
            (true, true) => 1,
            (true, false) => -1,
        },
        error: u32::from(g.error),
        mode,
        current_force: g.force_g as i32,
        temperature: g.temperature_c as i32,
        actpos: g.position as i32,
    }
}

fn status(s: &ArmState) -> ArmCurrentStatus {
    if !s.errors.is_empty() {
        return ArmCurrentStatus::Error;
    }
    match &s.status {
        None => ArmCurrentStatus::Unknown,
        Some(ArmStatus::Idle) => ArmCurrentStatus::Idle,
        Some(ArmStatus::Pause) => ArmCurrentStatus::Paused,
        Some(ArmStatus::Stop | ArmStatus::SlowStop) => ArmCurrentStatus::Stopped,
        Some(ArmStatus::Unknown(_)) => ArmCurrentStatus::Unknown,
        Some(_) => ArmCurrentStatus::Moving,
    }
}

/// One pushed sample in the API's units.
pub(crate) fn realtime(
    name: &str,
    since_connect: std::time::Duration,
    s: &ArmState,
    g: Option<GripperState>,
) -> ArmRealtimeState {
    ArmRealtimeState {
        name: name.to_string(),
        timestamp: SystemTime::now(),
        since_connect,
        joint_status: JointState {
            joint_position: s.joints_rad.iter().map(|r| r.to_degrees()).collect(),
            joint_speed: s
                .joint_speeds_rad_s
                .as_deref()
                .unwrap_or_default()
                .iter()
                .map(|w| w * RAD_S_TO_RPM)
                .collect(),
            joint_current: s.currents_a.iter().map(|a| a * 1000.0).collect(),
            joint_temperature: s.temperatures_c.clone(),
            joint_voltage: s.voltages_v.clone(),
            joint_err_code: s.joint_errors.iter().map(|e| u32::from(e.0)).collect(),
            joint_en_flag: s.enabled.clone(),
        },
        force_sensor: ArmForceSensor::default(),
        arm_current_status: status(s),
        gripper_state: g,
        ee_pose: pose_from_rm(&s.pose),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn driver_errors_map_to_their_codes() {
        let cases = [
            (
                RealmanError::Rejected {
                    command: "movej",
                    key: "receive_state",
                },
                AbcErrorCode::ArmCtrlFalse,
            ),
            (
                RealmanError::Timeout {
                    command: "movej",
                    after: std::time::Duration::from_millis(500),
                },
                AbcErrorCode::ArmTimeout,
            ),
            (
                RealmanError::Disconnected { command: "movej" },
                AbcErrorCode::ArmDataReceiveFailed,
            ),
            (
                RealmanError::Malformed {
                    command: "movej",
                    reason: "x".into(),
                },
                AbcErrorCode::ArmReturnDataErr,
            ),
            (
                RealmanError::Encode(EncodeError::OutOfRange {
                    field: "v",
                    value: 0,
                    min: 1,
                    max: 100,
                }),
                AbcErrorCode::ParamOutOfRange,
            ),
        ];
        for (e, code) in cases {
            assert_eq!(error(e).code, code);
        }
    }

    #[test]
    fn gripper_status_follows_online_and_enabled() {
        let g = rm::GripperState {
            enabled: false,
            online: true,
            error: 0b100,
            mode: GripperMode::ForceStopped,
            force_g: 350,
            temperature_c: 31,
            position: 420,
        };
        let a = gripper(&g);
        assert_eq!((a.status, a.error, a.mode, a.actpos), (-1, 4, 6, 420));
        assert_eq!(gripper(&rm::GripperState { online: false, ..g }).status, 0);
        assert_eq!(gripper(&rm::GripperState { enabled: true, ..g }).status, 1);
    }
}
