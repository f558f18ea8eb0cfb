//! Between the scenario's units and the Piper driver's wire-level API: scaling (mm to µm,
//! degrees to 0.001°/0.1°), "unchanged" sentinels, MIT code aliases, status-code names, and the
//! driver state as an [`Observation`]. Every Piper action is carried out here.

use std::collections::BTreeMap;
use std::future::Future;
use std::time::Duration;

use driver::piper::codec::{
    CollisionLevels, CtrlMode as WireCtrl, EndParams, EndPoseTarget, GripperTeachParams, IdOffset,
    InstallPosition, JointLimits, LeaderFollowerConfig, LinkageConfig, MitCommand, MitMode,
    ModeCtrl, MotionStatus, MotorSelect, MoveCPoint, MoveMode as WireMove, ParamCommand,
    ParamReset, Payload as WirePayload, UNCHANGED_U16,
};
use driver::piper::{GripperCommand, MoveKind, PiperError, PiperState};

use super::device::PiperDevice;
use super::model::{CtrlMode, Install, MoveMode, Payload, PiperAction, Pose, Role};
use super::observe::Observation;
use super::vocab;
use crate::harness::model::{ErrorClass, Near};
use crate::harness::{DeviceError, Reply};

/// Deadline of a `mode` step's confirmation on 0x2A1 when the step gives none.
const MODE_CONFIRM: Duration = Duration::from_millis(300);

pub(crate) fn classify(error: &PiperError) -> ErrorClass {
    match error {
        PiperError::Timeout { .. } | PiperError::EnableTimeout { .. } => ErrorClass::Timeout,
        PiperError::Rejected { .. } | PiperError::Decode { .. } => ErrorClass::Rejected,
        PiperError::Bus { .. } | PiperError::Disconnected | PiperError::AlreadyOwned { .. } => {
            ErrorClass::Bus
        }
        PiperError::OutOfLimit { .. }
        | PiperError::InvalidJoint { .. }
        | PiperError::InvalidValue { .. }
        | PiperError::Unsupported { .. } => ErrorClass::InvalidArgument,
    }
}

fn derr(error: PiperError) -> DeviceError {
    DeviceError::new(classify(&error), error.to_string())
}

fn um(mm: f64) -> i32 {
    (mm * 1000.0).round() as i32
}

fn target(pose: &Pose) -> EndPoseTarget {
    EndPoseTarget {
        x_um: um(pose.position_mm[0]),
        y_um: um(pose.position_mm[1]),
        z_um: um(pose.position_mm[2]),
        rx_mdeg: um(pose.orientation_deg[0]),
        ry_mdeg: um(pose.orientation_deg[1]),
        rz_mdeg: um(pose.orientation_deg[2]),
    }
}

/// Compare a reply value with its expectation, recording it either way.
fn check_near(reply: &mut Reply, key: &str, actual: f64, expected: Option<Near>, decimals: usize) {
    reply
        .values
        .push((key.to_owned(), format!("{actual:.decimals$}")));
    if let Some(e) = expected {
        if (actual - e.value).abs() > e.tolerance + 1e-9 {
            reply.mismatches.push((
                key.to_owned(),
                format!("{:.decimals$}", e.value),
                format!("{actual:.decimals$}"),
            ));
        }
    }
}

fn check_u(reply: &mut Reply, key: &str, actual: u16, expected: Option<u16>) {
    reply.values.push((key.to_owned(), actual.to_string()));
    if let Some(e) = expected {
        if e != actual {
            reply
                .mismatches
                .push((key.to_owned(), e.to_string(), actual.to_string()));
        }
    }
}

fn unchanged_or(value: Option<f64>, scale: f64) -> u16 {
    value.map_or(UNCHANGED_U16, |v| {
        (v * scale).round().clamp(0.0, f64::from(UNCHANGED_U16 - 1)) as u16
    })
}

fn ddeg(value: Option<f64>) -> i16 {
    value.map_or(UNCHANGED_U16 as i16, |v| {
        (v * 10.0).round().clamp(-32767.0, 32766.0) as i16
    })
}

fn move_name(mode: WireMove) -> String {
    match mode {
        WireMove::P => "p".to_owned(),
        WireMove::J => "j".to_owned(),
        WireMove::L => "l".to_owned(),
        WireMove::C => "c".to_owned(),
        WireMove::Mit | WireMove::MitV188 => "m".to_owned(),
        WireMove::Cpv => "cpv".to_owned(),
        other => format!("unknown(0x{:02X})", u8::from(other)),
    }
}

fn flag_names(bits: u8, names: &[(u8, &str)]) -> Vec<String> {
    let mut out: Vec<String> = names
        .iter()
        .filter(|(bit, _)| bits & (1 << bit) != 0)
        .map(|(_, n)| (*n).to_owned())
        .collect();
    out.sort();
    out
}

const JOINT_BITS: [(u8, &str); 7] = [
    (0, "under_voltage"),
    (1, "motor_over_temp"),
    (2, "over_current"),
    (3, "driver_over_temp"),
    (4, "collision"),
    (5, "driver_error"),
    (7, "stall"),
];

const GRIPPER_BITS: [(u8, &str); 6] = [
    (0, "under_voltage"),
    (1, "motor_over_temp"),
    (2, "over_current"),
    (3, "driver_over_temp"),
    (4, "sensor_fault"),
    (5, "driver_error"),
];

/// Feedback older than this counts as lost (10 feedback periods of 5 ms).
const FRESH: Duration = Duration::from_millis(50);

/// The harness's view of a driver state snapshot at tokio time `now`.
pub(crate) fn observe(state: &PiperState, now: tokio::time::Instant) -> Observation {
    let mut obs = Observation::default();
    if let Some(j) = &state.joints {
        obs.joints_deg = j
            .value
            .angles_mdeg
            .iter()
            .map(|a| f64::from(*a) / 1000.0)
            .collect();
    }
    if state.high_speed.iter().any(Option::is_some) {
        obs.speeds_deg_s = state
            .high_speed
            .iter()
            .map(|h| {
                h.as_ref().map_or(f64::NAN, |h| {
                    f64::from(h.value.speed_mrad_s).to_degrees() / 1000.0
                })
            })
            .collect();
        obs.currents_a = state
            .high_speed
            .iter()
            .map(|h| {
                h.as_ref()
                    .map_or(f64::NAN, |h| f64::from(h.value.current_ma) / 1000.0)
            })
            .collect();
    }
    if state.low_speed.iter().any(Option::is_some) {
        obs.motor_temps_c = state
            .low_speed
            .iter()
            .map(|l| {
                l.as_ref()
                    .map_or(f64::NAN, |l| f64::from(l.value.motor_temp_c))
            })
            .collect();
        obs.enabled = state
            .low_speed
            .iter()
            .map(|l| l.as_ref().is_some_and(|l| l.value.status.enabled()))
            .collect();
        obs.joint_flags = state
            .low_speed
            .iter()
            .map(|l| {
                l.as_ref()
                    .map_or_else(Vec::new, |l| flag_names(l.value.status.0, &JOINT_BITS))
            })
            .collect();
    }
    if let Some(p) = &state.end_pose {
        let p = &p.value;
        obs.position_mm = Some([p.x_um, p.y_um, p.z_um].map(|v| f64::from(v) / 1000.0));
        obs.orientation_deg =
            Some([p.rx_mdeg, p.ry_mdeg, p.rz_mdeg].map(|v| f64::from(v) / 1000.0));
    }
    if let Some(g) = &state.gripper {
        obs.gripper_mm = Some(f64::from(g.value.stroke_um) / 1000.0);
        obs.gripper_enabled = Some(g.value.status.enabled());
        obs.gripper_flags = flag_names(g.value.status.0, &GRIPPER_BITS);
    }
    let mut status: BTreeMap<&'static str, String> = BTreeMap::new();
    if let Some(a) = &state.arm_status {
        let a = &a.value;
        let code = u8::from(a.arm_status);
        obs.arm_status_code = Some(code);
        status.insert("arm_status", vocab::name_of(&vocab::ARM_STATUS, code));
        status.insert(
            "ctrl_mode",
            vocab::name_of(&vocab::CTRL_MODE, u8::from(a.ctrl_mode)),
        );
        status.insert("move_mode", move_name(a.mode_feed));
        status.insert(
            "motion",
            match a.motion_status {
                MotionStatus::Reached => "reached".to_owned(),
                MotionStatus::Moving => "moving".to_owned(),
                MotionStatus::Unknown(raw) => format!("unknown(0x{raw:02X})"),
            },
        );
        obs.comm_error_joints = a.comm_error.joints();
        obs.limit_error_joints = a.angle_limit_exceeded.joints();
    }
    let fresh = |at: Option<tokio::time::Instant>| {
        at.is_some_and(|at| now.saturating_duration_since(at) <= FRESH)
    };
    let joints_fresh = fresh(state.joints.as_ref().map(|j| j.received_at));
    status.insert(
        "feedback",
        if joints_fresh { "alive" } else { "lost" }.to_owned(),
    );
    let leader_fresh = fresh(state.joint_cmd_echo.as_ref().map(|j| j.received_at));
    status.insert("leader_frames", leader_fresh.to_string());
    obs.status = status;
    obs
}

impl PiperDevice {
    async fn within<T>(
        timeout: Option<Duration>,
        what: &str,
        fut: impl Future<Output = Result<T, PiperError>>,
    ) -> Result<T, DeviceError> {
        match timeout {
            Some(limit) => match tokio::time::timeout(limit, fut).await {
                Ok(r) => r.map_err(derr),
                Err(_) => Err(DeviceError::new(
                    ErrorClass::Timeout,
                    format!("{what}: no confirmation within {} ms", limit.as_millis()),
                )),
            },
            None => fut.await.map_err(derr),
        }
    }

    /// Carry out a Piper action through the driver.
    pub(super) async fn act(
        &self,
        action: &PiperAction,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let d = &self.driver;
        let mut reply = Reply::default();
        match action {
            PiperAction::Enable { joints, gripper } => {
                if joints.is_empty() {
                    let select = if *gripper {
                        MotorSelect::AllWithGripper
                    } else {
                        MotorSelect::All
                    };
                    Self::within(timeout, "enable", d.enable(select)).await?;
                } else {
                    for j in joints {
                        Self::within(timeout, "enable", d.enable(MotorSelect::Joint(*j))).await?;
                    }
                }
            }
            PiperAction::Disable { joints } => {
                if joints.is_empty() {
                    Self::within(timeout, "disable", d.disable(MotorSelect::All)).await?;
                } else {
                    for j in joints {
                        Self::within(timeout, "disable", d.disable(MotorSelect::Joint(*j))).await?;
                    }
                }
            }
            PiperAction::Mode {
                ctrl,
                move_mode,
                speed_pct,
                mit,
                install,
            } => {
                let kind = match move_mode {
                    MoveMode::P => MoveKind::P,
                    MoveMode::J => MoveKind::J,
                    MoveMode::L => MoveKind::L,
                    MoveMode::C => MoveKind::C,
                    MoveMode::M => MoveKind::Mit,
                };
                let (code, _) = d.move_mode_code(kind);
                let command = ModeCtrl {
                    ctrl_mode: match ctrl {
                        CtrlMode::Can => WireCtrl::CanCommand,
                        CtrlMode::Standby => WireCtrl::Standby,
                    },
                    move_mode: code,
                    speed_pct: *speed_pct,
                    mit_mode: if *mit {
                        MitMode::Mit
                    } else {
                        MitMode::PositionVelocity
                    },
                    dwell_s: 0,
                    install_pos: match install {
                        None => InstallPosition::Unchanged,
                        Some(Install::Upright) => InstallPosition::Upright,
                        Some(Install::Left) => InstallPosition::SideLeft,
                        Some(Install::Right) => InstallPosition::SideRight,
                    },
                };
                d.mode_ctrl(command).await.map_err(derr)?;
                if *ctrl == CtrlMode::Can {
                    let limit = timeout.unwrap_or(self.options.deadline(MODE_CONFIRM));
                    d.wait_for_move_mode(kind, limit).await.map_err(derr)?;
                }
            }
            PiperAction::MoveJ {
                joints_deg,
                speed_pct,
            } => {
                let rad = joints_deg.map(f64::to_radians);
                Self::within(timeout, "move_j", d.move_joints_rad(rad, *speed_pct)).await?;
            }
            PiperAction::MoveP { pose, speed_pct } | PiperAction::MoveL { pose, speed_pct } => {
                let kind = if matches!(action, PiperAction::MoveP { .. }) {
                    MoveKind::P
                } else {
                    MoveKind::L
                };
                d.set_move_mode(kind, *speed_pct).await.map_err(derr)?;
                d.end_pose(target(pose)).await.map_err(derr)?;
            }
            PiperAction::MoveC {
                start,
                middle,
                end,
                speed_pct,
            } => {
                for (pose, point) in [
                    (start, MoveCPoint::Start),
                    (middle, MoveCPoint::Middle),
                    (end, MoveCPoint::End),
                ] {
                    d.end_pose(target(pose)).await.map_err(derr)?;
                    d.move_c_point(point).await.map_err(derr)?;
                }
                d.set_move_mode(MoveKind::C, *speed_pct)
                    .await
                    .map_err(derr)?;
            }
            PiperAction::Mit {
                joint,
                position_deg,
                velocity_deg_s,
                kp,
                kd,
                torque_nm,
            } => {
                let command = MitCommand {
                    p_rad: position_deg.to_radians(),
                    v_rad_s: velocity_deg_s.to_radians(),
                    kp: *kp,
                    kd: *kd,
                    t_nm: *torque_nm,
                };
                d.mit(*joint, command).await.map_err(derr)?;
            }
            PiperAction::Gripper {
                stroke_mm,
                torque_nm,
                enable,
                clear_error,
            } => {
                d.gripper(GripperCommand {
                    stroke_m: stroke_mm / 1000.0,
                    effort_nm: *torque_nm,
                    enable: *enable,
                    clear_error: *clear_error,
                })
                .await
                .map_err(derr)?;
            }
            PiperAction::GripperZero => d.gripper_set_zero().await.map_err(derr)?,
            PiperAction::Estop => d.emergency_stop().await.map_err(derr)?,
            PiperAction::Reset => d.reset().await.map_err(derr)?,
            PiperAction::QueryFirmware { expect } => {
                let info = Self::within(timeout, "query_firmware", d.query_firmware()).await?;
                reply
                    .values
                    .push(("firmware".to_owned(), info.software.clone()));
                if let Some(e) = expect {
                    if *e != info.software {
                        reply.mismatches.push((
                            "firmware".to_owned(),
                            e.clone(),
                            info.software.clone(),
                        ));
                    }
                }
            }
            PiperAction::QueryJointLimits {
                joint,
                min_deg,
                max_deg,
                max_speed_rad_s,
            } => {
                let l = Self::within(timeout, "query_joint_limits", d.query_joint_limits(*joint))
                    .await?;
                check_near(
                    &mut reply,
                    "min_deg",
                    f64::from(l.min_angle_ddeg) / 10.0,
                    *min_deg,
                    1,
                );
                check_near(
                    &mut reply,
                    "max_deg",
                    f64::from(l.max_angle_ddeg) / 10.0,
                    *max_deg,
                    1,
                );
                check_near(
                    &mut reply,
                    "max_speed_rad_s",
                    f64::from(l.max_speed_crad_s) / 100.0,
                    *max_speed_rad_s,
                    2,
                );
            }
            PiperAction::QueryJointAcc {
                joint,
                max_acc_rad_s2,
            } => {
                let a = Self::within(
                    timeout,
                    "query_joint_max_acc",
                    d.query_joint_max_acc(*joint),
                )
                .await?;
                check_near(
                    &mut reply,
                    "max_acc_rad_s2",
                    f64::from(a.max_acc_crad_s2) / 100.0,
                    *max_acc_rad_s2,
                    2,
                );
            }
            PiperAction::QueryEndLimits { expect } => {
                let p = Self::within(timeout, "query_end_limits", d.query_end_params()).await?;
                let values = [
                    p.lin_vel_mm_s,
                    p.ang_vel_mrad_s,
                    p.lin_acc_mm_s2,
                    p.ang_acc_mrad_s2,
                ];
                let keys = [
                    "linear_m_s",
                    "angular_rad_s",
                    "linear_acc_m_s2",
                    "angular_acc_rad_s2",
                ];
                for ((key, raw), e) in keys.iter().zip(values).zip(expect) {
                    check_near(&mut reply, key, f64::from(raw) / 1000.0, *e, 3);
                }
            }
            PiperAction::QueryCollision { expect } => {
                let c = Self::within(
                    timeout,
                    "query_collision_levels",
                    d.query_collision_levels(),
                )
                .await?;
                let text = format!("{:?}", c.levels);
                reply.values.push(("levels".to_owned(), text.clone()));
                if let Some(e) = expect {
                    if *e != c.levels {
                        reply
                            .mismatches
                            .push(("levels".to_owned(), format!("{e:?}"), text));
                    }
                }
            }
            PiperAction::QueryGripperParams { expect } => {
                let g = Self::within(
                    timeout,
                    "query_gripper_params",
                    d.query_gripper_teach_params(),
                )
                .await?;
                check_u(
                    &mut reply,
                    "max_stroke_mm",
                    u16::from(g.max_stroke_mm),
                    expect[0],
                );
                check_u(
                    &mut reply,
                    "teach_coefficient_pct",
                    u16::from(g.teach_coef_pct),
                    expect[1],
                );
                check_u(&mut reply, "friction", u16::from(g.friction), expect[2]);
            }
            PiperAction::SetJointLimits {
                joint,
                min_deg,
                max_deg,
                max_speed_rad_s,
            } => {
                let limits = JointLimits {
                    joint: *joint,
                    max_angle_ddeg: ddeg(*max_deg),
                    min_angle_ddeg: ddeg(*min_deg),
                    max_speed_crad_s: unchanged_or(*max_speed_rad_s, 100.0),
                };
                Self::within(timeout, "set_joint_limits", d.set_joint_limits(limits)).await?;
            }
            PiperAction::SetJointAcc {
                joint,
                max_acc_rad_s2,
            } => {
                let raw = (max_acc_rad_s2 * 100.0).round() as u16;
                Self::within(
                    timeout,
                    "set_joint_max_acc",
                    d.set_joint_max_acc(*joint, raw),
                )
                .await?;
            }
            PiperAction::SetEndLimits { values } => {
                let params = EndParams {
                    lin_vel_mm_s: unchanged_or(values[0], 1000.0),
                    ang_vel_mrad_s: unchanged_or(values[1], 1000.0),
                    lin_acc_mm_s2: unchanged_or(values[2], 1000.0),
                    ang_acc_mrad_s2: unchanged_or(values[3], 1000.0),
                };
                Self::within(timeout, "set_end_limits", d.set_end_params(params)).await?;
            }
            PiperAction::SetCollision { levels } => {
                Self::within(
                    timeout,
                    "set_collision_levels",
                    d.set_collision_levels(CollisionLevels { levels: *levels }),
                )
                .await?;
            }
            PiperAction::SetGripperParams {
                max_stroke_mm,
                teach_coefficient_pct,
                friction,
            } => {
                // 0x47D has no "unchanged" value: start from the arm's current parameters.
                let current = Self::within(
                    timeout,
                    "set_gripper_params",
                    d.query_gripper_teach_params(),
                )
                .await?;
                let narrow =
                    |v: Option<u16>, old: u8| v.map_or(old, |v| u8::try_from(v).unwrap_or(u8::MAX));
                let params = GripperTeachParams {
                    teach_coef_pct: narrow(*teach_coefficient_pct, current.teach_coef_pct),
                    max_stroke_mm: narrow(*max_stroke_mm, current.max_stroke_mm),
                    friction: narrow(*friction, current.friction),
                };
                d.set_gripper_teach_params(params).await.map_err(derr)?;
            }
            PiperAction::SetZero { joint } => {
                Self::within(timeout, "set_zero", d.set_joint_zero(*joint)).await?;
            }
            PiperAction::ClearJointError { joint } => {
                Self::within(timeout, "clear_joint_error", d.clear_joint_error(*joint)).await?;
            }
            PiperAction::ResetParams => {
                let command = ParamCommand {
                    reset: Some(ParamReset::JointParams),
                    ..ParamCommand::default()
                };
                Self::within(timeout, "reset_params", d.param_settings(command)).await?;
            }
            PiperAction::SetPayload { payload } => {
                let p = match payload {
                    Payload::Empty => WirePayload::Empty,
                    Payload::Half => WirePayload::Half,
                    Payload::Full => WirePayload::Full,
                };
                let command = ParamCommand {
                    payload: Some(p),
                    ..ParamCommand::default()
                };
                Self::within(timeout, "set_payload", d.param_settings(command)).await?;
            }
            PiperAction::SetRole {
                role,
                feedback_offset,
                control_offset,
                target_offset,
            } => {
                let config = LeaderFollowerConfig {
                    linkage: match role {
                        Role::Leader => LinkageConfig::Leader,
                        Role::Follower => LinkageConfig::Follower,
                    },
                    feedback_offset: IdOffset::from(*feedback_offset),
                    ctrl_offset: IdOffset::from(*control_offset),
                    target_offset: IdOffset::from(*target_offset),
                };
                d.set_leader_follower(config).await.map_err(derr)?;
            }
        }
        Ok(reply)
    }
}
