//! Piper actions through the driver's SI API. The harness only maps scenario units (degrees,
//! millimetres) to SI; scaling to wire integers, "unchanged" codes and per-firmware codes
//! are the driver's business.

use std::future::Future;
use std::time::Duration;

use driver::piper::{
    ArmRole, CtrlMode as DriverCtrl, EndLimitsUpdate, EndPayload, GripperTeachUpdate, IdShift,
    Install as DriverInstall, JointLimitsUpdate, JointSelect, MitCommand, ModeCommand, MotorSelect,
    MoveKind, PiperError, Pose as DriverPose, RoleOffsets,
};

use super::stream;
use super::PiperDevice;
use crate::devices::piper::model::{CtrlMode, Install, MoveMode, Payload, PiperAction, Pose, Role};
use crate::devices::{within, DeviceError, Reply};
use crate::scenario::{ErrorClass, Near};

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

fn invalid(text: String) -> DeviceError {
    DeviceError::new(ErrorClass::InvalidArgument, text)
}

pub(super) fn pose(pose: &Pose) -> DriverPose {
    DriverPose {
        position_m: pose.position_mm.map(|mm| mm / 1000.0),
        orientation_rad: pose.orientation_deg.map(f64::to_radians),
    }
}

/// Joint 1–6, or 7 for all (the scenario's spelling).
fn joint_select(joint: u8) -> JointSelect {
    if joint == 7 {
        JointSelect::All
    } else {
        JointSelect::Joint(joint)
    }
}

fn shift(offset: u8, key: &str) -> Result<IdShift, DeviceError> {
    IdShift::from_ids(u16::from(offset))
        .ok_or_else(|| invalid(format!("{key} {offset:#04x} is not 0, 0x10 or 0x20")))
}

fn narrow(value: Option<u16>, key: &str) -> Result<Option<u8>, DeviceError> {
    value
        .map(|v| u8::try_from(v).map_err(|_| invalid(format!("{key} {v} is above 255"))))
        .transpose()
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

impl PiperDevice {
    async fn within<T>(
        timeout: Option<Duration>,
        what: &str,
        fut: impl Future<Output = Result<T, PiperError>>,
    ) -> Result<T, DeviceError> {
        let late = || format!("{what}: no confirmation");
        within(timeout, late, async { fut.await.map_err(derr) }).await
    }

    /// Carry out a Piper action through the driver.
    pub(super) async fn act(
        &self,
        action: &PiperAction,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        match action {
            PiperAction::Enable { .. }
            | PiperAction::Disable { .. }
            | PiperAction::Mode { .. }
            | PiperAction::MoveJ { .. }
            | PiperAction::MoveP { .. }
            | PiperAction::MoveL { .. }
            | PiperAction::MoveC { .. }
            | PiperAction::Mit { .. }
            | PiperAction::Gripper { .. }
            | PiperAction::GripperZero
            | PiperAction::Estop
            | PiperAction::Reset => {
                if let Some(part) = stream::part_of(action) {
                    self.streams.stop(part);
                }
                self.motion(action, timeout).await?;
                if let Some(period) = stream::period_of(action) {
                    self.streams.start(&self.driver, action, period);
                }
                Ok(Reply::default())
            }
            PiperAction::QueryFirmware { .. }
            | PiperAction::QueryJointLimits { .. }
            | PiperAction::QueryJointAcc { .. }
            | PiperAction::QueryEndLimits { .. }
            | PiperAction::QueryCollision { .. }
            | PiperAction::QueryGripperParams { .. } => self.query(action, timeout).await,
            _ => self
                .settings(action, timeout)
                .await
                .map(|()| Reply::default()),
        }
    }

    /// Enable, modes, motion, MIT, gripper, stop.
    async fn motion(
        &self,
        action: &PiperAction,
        timeout: Option<Duration>,
    ) -> Result<(), DeviceError> {
        let d = &self.driver;
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
                let command = ModeCommand {
                    control: match ctrl {
                        CtrlMode::Can => DriverCtrl::CanCommand,
                        CtrlMode::Standby => DriverCtrl::Standby,
                    },
                    move_kind: kind,
                    speed_pct: *speed_pct,
                    mit_flag: Some(*mit),
                    install: install.map(|i| match i {
                        Install::Upright => DriverInstall::Upright,
                        Install::Left => DriverInstall::SideLeft,
                        Install::Right => DriverInstall::SideRight,
                    }),
                };
                d.set_mode(command).await.map_err(derr)?;
                if *ctrl == CtrlMode::Can {
                    let limit = timeout.unwrap_or(self.options.deadline(MODE_CONFIRM));
                    d.wait_for_move_mode(kind, limit).await.map_err(derr)?;
                }
            }
            // Shared with `every_ms` re-sends, which send exactly what the step sent.
            PiperAction::MoveJ { .. } => {
                let send = async { stream::send_command(d, action).await.unwrap_or(Ok(())) };
                Self::within(timeout, "move_j", send).await?;
            }
            PiperAction::MoveP { .. }
            | PiperAction::MoveL { .. }
            | PiperAction::MoveC { .. }
            | PiperAction::Gripper { .. } => {
                let sent = stream::send_command(d, action).await;
                sent.unwrap_or(Ok(())).map_err(derr)?;
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
            PiperAction::GripperZero => d.gripper_set_zero().await.map_err(derr)?,
            PiperAction::Estop => d.emergency_stop().await.map_err(derr)?,
            PiperAction::Reset => d.reset().await.map_err(derr)?,
            other => {
                return Err(DeviceError::unsupported(format!(
                    "not a motion action: {other:?}"
                )))
            }
        }
        Ok(())
    }

    /// Queries: the reply's values in scenario units, with mismatches against expectations.
    async fn query(
        &self,
        action: &PiperAction,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let d = &self.driver;
        let mut reply = Reply::default();
        match action {
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
                check_near(&mut reply, "min_deg", l.min_rad.to_degrees(), *min_deg, 1);
                check_near(&mut reply, "max_deg", l.max_rad.to_degrees(), *max_deg, 1);
                let speed = l.max_speed_rad_s;
                check_near(&mut reply, "max_speed_rad_s", speed, *max_speed_rad_s, 2);
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
                check_near(&mut reply, "max_acc_rad_s2", a, *max_acc_rad_s2, 2);
            }
            PiperAction::QueryEndLimits { expect } => {
                let p = Self::within(timeout, "query_end_limits", d.query_end_limits()).await?;
                let values = [
                    ("linear_m_s", p.linear_m_s),
                    ("angular_rad_s", p.angular_rad_s),
                    ("linear_acc_m_s2", p.linear_acc_m_s2),
                    ("angular_acc_rad_s2", p.angular_acc_rad_s2),
                ];
                for ((key, value), e) in values.into_iter().zip(expect) {
                    check_near(&mut reply, key, value, *e, 3);
                }
            }
            PiperAction::QueryCollision { expect } => {
                let levels = Self::within(
                    timeout,
                    "query_collision_levels",
                    d.query_collision_levels(),
                )
                .await?;
                let text = format!("{levels:?}");
                reply.values.push(("levels".to_owned(), text.clone()));
                if let Some(e) = expect {
                    if *e != levels {
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
                let stroke_mm = (g.max_stroke_m * 1000.0).round() as u16;
                check_u(&mut reply, "max_stroke_mm", stroke_mm, expect[0]);
                let coefficient = u16::from(g.teach_coefficient_pct);
                check_u(&mut reply, "teach_coefficient_pct", coefficient, expect[1]);
                check_u(&mut reply, "friction", u16::from(g.friction), expect[2]);
            }
            other => return Err(DeviceError::unsupported(format!("not a query: {other:?}"))),
        }
        Ok(reply)
    }

    /// Settings (acknowledged by the arm where it acknowledges).
    async fn settings(
        &self,
        action: &PiperAction,
        timeout: Option<Duration>,
    ) -> Result<(), DeviceError> {
        let d = &self.driver;
        match action {
            PiperAction::SetJointLimits {
                joint,
                min_deg,
                max_deg,
                max_speed_rad_s,
            } => {
                let update = JointLimitsUpdate {
                    min_rad: min_deg.map(f64::to_radians),
                    max_rad: max_deg.map(f64::to_radians),
                    max_speed_rad_s: *max_speed_rad_s,
                };
                let fut = d.set_joint_limits(*joint, update);
                Self::within(timeout, "set_joint_limits", fut).await?;
            }
            PiperAction::SetJointAcc {
                joint,
                max_acc_rad_s2,
            } => {
                let fut = d.set_joint_max_acc(joint_select(*joint), *max_acc_rad_s2);
                Self::within(timeout, "set_joint_max_acc", fut).await?;
            }
            PiperAction::SetEndLimits { values } => {
                let update = EndLimitsUpdate {
                    linear_m_s: values[0],
                    angular_rad_s: values[1],
                    linear_acc_m_s2: values[2],
                    angular_acc_rad_s2: values[3],
                };
                Self::within(timeout, "set_end_limits", d.set_end_limits(update)).await?;
            }
            PiperAction::SetCollision { levels } => {
                let fut = d.set_collision_levels(levels.map(Some));
                Self::within(timeout, "set_collision_levels", fut).await?;
            }
            PiperAction::SetGripperParams {
                max_stroke_mm,
                teach_coefficient_pct,
                friction,
            } => {
                let update = GripperTeachUpdate {
                    teach_coefficient_pct: narrow(*teach_coefficient_pct, "teach_coefficient_pct")?,
                    max_stroke_m: max_stroke_mm.map(|mm| f64::from(mm) / 1000.0),
                    friction: narrow(*friction, "friction")?,
                };
                let fut = d.set_gripper_teach_params(update);
                Self::within(timeout, "set_gripper_params", fut).await?;
            }
            PiperAction::SetZero { joint } => {
                let fut = d.set_joint_zero(joint_select(*joint));
                Self::within(timeout, "set_zero", fut).await?;
            }
            PiperAction::ClearJointError { joint } => {
                let fut = d.clear_joint_error(joint_select(*joint));
                Self::within(timeout, "clear_joint_error", fut).await?;
            }
            PiperAction::ResetParams => {
                Self::within(timeout, "reset_params", d.reset_joint_params()).await?;
            }
            PiperAction::SetPayload { payload } => {
                let payload = match payload {
                    Payload::Empty => EndPayload::Empty,
                    Payload::Half => EndPayload::Half,
                    Payload::Full => EndPayload::Full,
                };
                Self::within(timeout, "set_payload", d.set_payload(payload)).await?;
            }
            PiperAction::SetRole {
                role,
                feedback_offset,
                control_offset,
                target_offset,
            } => {
                let role = match role {
                    Role::Leader => ArmRole::Leader,
                    Role::Follower => ArmRole::Follower,
                };
                let offsets = RoleOffsets {
                    feedback: shift(*feedback_offset, "feedback_offset")?,
                    control: shift(*control_offset, "control_offset")?,
                    target: shift(*target_offset, "target_offset")?,
                };
                d.set_role(Some(role), offsets).await.map_err(derr)?;
            }
            other => {
                return Err(DeviceError::unsupported(format!(
                    "not a setting: {other:?}"
                )))
            }
        }
        Ok(())
    }
}
