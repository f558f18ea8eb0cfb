//! Conversions between the wire structs of this codec and the SI / typed values of the public
//! API (`piper::types`). Scaling, rounding, "unchanged" sentinels and per-firmware codes are
//! decided here and nowhere else.

use super::{
    ArmStatus as WireArmStatus, CollisionLevels, CtrlMode, EndParams, EndPosePart, EndPoseTarget,
    EndVelAccFeedback, FirmwareVersion, GripperCtrl, GripperFeedback,
    GripperTeachParams as WireGripperTeach, HighSpeedFeedback, IdOffset, InstallPosition,
    JointLimits as WireJointLimits, JointTargets, LinkageConfig, LowSpeedFeedback, MitMode,
    ModeCtrl, MoveCPoint, MoveMode, Payload, UNCHANGED_U16,
};
use crate::piper::types::{
    ActiveMove, ArmRole, ArmStatus, CirclePoint, DriverState, EndLimits, EndLimitsUpdate,
    EndMotion, EndPayload, GripperCommand, GripperState, GripperTeachParams, GripperTeachUpdate,
    IdShift, Install, JointLimits, JointLimitsUpdate, JointSelect, LeaderMode, ModeCommand,
    MotorState, MoveKind, Pose,
};

/// A value the wire cannot carry (non-finite, negative where unsigned, too large).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RangeError {
    /// The argument's name.
    pub field: &'static str,
    /// The value given.
    pub value: f64,
}

/// Millidegrees to radians.
pub fn mdeg_to_rad(mdeg: i32) -> f64 {
    (f64::from(mdeg) / 1000.0).to_radians()
}

/// Radians to millidegrees, rounded to the nearest integer and saturated to i32.
pub fn rad_to_mdeg(rad: f64) -> i32 {
    (rad.to_degrees() * 1000.0).round() as i32
}

fn um_to_m(um: i32) -> f64 {
    f64::from(um) * 1e-6
}

/// Metres to µm, rounded and saturated (position fields are int32 on the wire).
fn m_to_um(m: f64) -> i32 {
    (m * 1e6).round() as i32
}

/// `value × scale` as an unsigned 16-bit field below the 0x7FFF "unchanged" code; `None`
/// sends that code.
fn keep_or_u16(field: &'static str, value: Option<f64>, scale: f64) -> Result<u16, RangeError> {
    let Some(value) = value else {
        return Ok(UNCHANGED_U16);
    };
    let scaled = (value * scale).round();
    if scaled.is_finite() && (0.0..f64::from(UNCHANGED_U16)).contains(&scaled) {
        Ok(scaled as u16)
    } else {
        Err(RangeError { field, value })
    }
}

/// An angle in rad as a signed 0.1° field below the 0x7FFF "unchanged" code.
fn keep_or_ddeg(field: &'static str, value: Option<f64>) -> Result<i16, RangeError> {
    let Some(value) = value else {
        return Ok(UNCHANGED_U16 as i16);
    };
    let scaled = (value.to_degrees() * 10.0).round();
    if scaled.is_finite() && (-32767.0..32767.0).contains(&scaled) {
        Ok(scaled as i16)
    } else {
        Err(RangeError { field, value })
    }
}

/// The wire MOVE-mode code and MIT flag of `kind` on `firmware` (MIT is 0x04, or 0x06 from
/// S-V1.8-8; unknown firmware gets the older code).
pub(crate) fn move_code(kind: MoveKind, firmware: Option<FirmwareVersion>) -> (MoveMode, MitMode) {
    match kind {
        MoveKind::P => (MoveMode::P, MitMode::PositionVelocity),
        MoveKind::J => (MoveMode::J, MitMode::PositionVelocity),
        MoveKind::L => (MoveMode::L, MitMode::PositionVelocity),
        MoveKind::C => (MoveMode::C, MitMode::PositionVelocity),
        MoveKind::Cpv => (MoveMode::Cpv, MitMode::PositionVelocity),
        MoveKind::HighFollow => (MoveMode::J, MitMode::Mit),
        MoveKind::Mit => (
            firmware.map_or(MoveMode::Mit, FirmwareVersion::mit_move_mode),
            MitMode::Mit,
        ),
    }
}

/// The MOVE mode a reported code means; `None` for the "unchanged" code.
pub(crate) fn active_move(code: MoveMode) -> Option<ActiveMove> {
    Some(match code {
        MoveMode::P => ActiveMove::P,
        MoveMode::J => ActiveMove::J,
        MoveMode::L => ActiveMove::L,
        MoveMode::C => ActiveMove::C,
        MoveMode::Mit | MoveMode::MitV188 => ActiveMove::Mit,
        MoveMode::Cpv => ActiveMove::Cpv,
        MoveMode::Unchanged => return None,
        MoveMode::Unknown(raw) => ActiveMove::Unknown(raw),
    })
}

fn install_code(install: Option<Install>) -> InstallPosition {
    match install {
        None => InstallPosition::Unchanged,
        Some(Install::Upright) => InstallPosition::Upright,
        Some(Install::SideLeft) => InstallPosition::SideLeft,
        Some(Install::SideRight) => InstallPosition::SideRight,
    }
}

fn install_of(code: InstallPosition) -> Option<Install> {
    match code {
        InstallPosition::Upright => Some(Install::Upright),
        InstallPosition::SideLeft => Some(Install::SideLeft),
        InstallPosition::SideRight => Some(Install::SideRight),
        InstallPosition::Unchanged | InstallPosition::Unknown(_) => None,
    }
}

/// A typed mode command as 0x151, for `firmware`.
pub(crate) fn mode_ctrl(command: &ModeCommand, firmware: Option<FirmwareVersion>) -> ModeCtrl {
    let (move_mode, implied) = move_code(command.move_kind, firmware);
    let mit_mode = match command.mit_flag {
        None => implied,
        Some(true) => MitMode::Mit,
        Some(false) => MitMode::PositionVelocity,
    };
    ModeCtrl {
        ctrl_mode: command.control,
        move_mode,
        speed_pct: command.speed_pct,
        mit_mode,
        dwell_s: 0,
        install_pos: install_code(command.install),
    }
}

/// Only the installation position, every other field "unchanged".
pub(crate) fn install_only(install: Install) -> ModeCtrl {
    ModeCtrl {
        ctrl_mode: CtrlMode::CanCommand,
        move_mode: MoveMode::Unchanged,
        speed_pct: 0,
        mit_mode: MitMode::Ignore,
        dwell_s: 0,
        install_pos: install_code(Some(install)),
    }
}

/// A leader arm's 0x151 in typed form.
pub(crate) fn leader_mode(mode: &ModeCtrl) -> LeaderMode {
    LeaderMode {
        control: mode.ctrl_mode,
        move_mode: active_move(mode.move_mode),
        speed_pct: mode.speed_pct,
        mit_flag: mode.mit_mode == MitMode::Mit,
        install: install_of(mode.install_pos),
    }
}

/// Joint targets in rad as 0x155–0x157.
pub(crate) fn joint_targets(targets_rad: [f64; 6]) -> JointTargets {
    JointTargets {
        angles_mdeg: targets_rad.map(rad_to_mdeg),
    }
}

/// A pose as 0x152–0x154 (µm and millidegrees).
pub(crate) fn end_pose_target(pose: &Pose) -> EndPoseTarget {
    let [x_um, y_um, z_um] = pose.position_m.map(m_to_um);
    let [rx_mdeg, ry_mdeg, rz_mdeg] = pose.orientation_rad.map(rad_to_mdeg);
    EndPoseTarget {
        x_um,
        y_um,
        z_um,
        rx_mdeg,
        ry_mdeg,
        rz_mdeg,
    }
}

/// Merge one 0x2A2–0x2A4 frame into a pose.
pub(crate) fn apply_end_pose(pose: &mut Pose, part: &EndPosePart) {
    match *part {
        EndPosePart::Xy { x_um, y_um } => {
            pose.position_m[0] = um_to_m(x_um);
            pose.position_m[1] = um_to_m(y_um);
        }
        EndPosePart::ZRx { z_um, rx_mdeg } => {
            pose.position_m[2] = um_to_m(z_um);
            pose.orientation_rad[0] = mdeg_to_rad(rx_mdeg);
        }
        EndPosePart::RyRz { ry_mdeg, rz_mdeg } => {
            pose.orientation_rad[1] = mdeg_to_rad(ry_mdeg);
            pose.orientation_rad[2] = mdeg_to_rad(rz_mdeg);
        }
    }
}

/// The 0x158 point code.
pub(crate) fn circle_point(point: CirclePoint) -> MoveCPoint {
    match point {
        CirclePoint::Start => MoveCPoint::Start,
        CirclePoint::Middle => MoveCPoint::Middle,
        CirclePoint::End => MoveCPoint::End,
    }
}

/// A gripper command (stroke already limit-checked) as 0x159.
pub(crate) fn gripper_ctrl(command: &GripperCommand) -> Result<GripperCtrl, RangeError> {
    let effort = (command.effort_nm * 1000.0).round();
    if !(effort.is_finite() && (0.0..=f64::from(u16::MAX)).contains(&effort)) {
        return Err(RangeError {
            field: "effort_nm",
            value: command.effort_nm,
        });
    }
    if !command.stroke_m.is_finite() {
        return Err(RangeError {
            field: "stroke_m",
            value: command.stroke_m,
        });
    }
    Ok(GripperCtrl {
        stroke_um: m_to_um(command.stroke_m),
        effort_mnm: effort as u16,
        enable: command.enable,
        clear_error: command.clear_error,
        set_zero: false,
    })
}

/// A (leader's) 0x159 in SI units.
pub(crate) fn gripper_command(ctrl: &GripperCtrl) -> GripperCommand {
    GripperCommand {
        stroke_m: um_to_m(ctrl.stroke_um),
        effort_nm: f64::from(ctrl.effort_mnm) * 1e-3,
        enable: ctrl.enable,
        clear_error: ctrl.clear_error,
    }
}

/// The joint byte of 0x475 (1–6, 7 = all).
pub(crate) fn joint_select(select: JointSelect) -> u8 {
    match select {
        JointSelect::Joint(joint) => joint,
        JointSelect::All => 7,
    }
}

/// A joint-limit change as 0x474.
pub(crate) fn joint_limits_set(
    joint: u8,
    update: &JointLimitsUpdate,
) -> Result<WireJointLimits, RangeError> {
    Ok(WireJointLimits {
        joint,
        max_angle_ddeg: keep_or_ddeg("max_rad", update.max_rad)?,
        min_angle_ddeg: keep_or_ddeg("min_rad", update.min_rad)?,
        max_speed_crad_s: keep_or_u16("max_speed_rad_s", update.max_speed_rad_s, 100.0)?,
    })
}

/// A 0x473 reply in SI units.
pub(crate) fn joint_limits(wire: &WireJointLimits) -> JointLimits {
    JointLimits {
        joint: wire.joint,
        min_rad: (f64::from(wire.min_angle_ddeg) / 10.0).to_radians(),
        max_rad: (f64::from(wire.max_angle_ddeg) / 10.0).to_radians(),
        max_speed_rad_s: f64::from(wire.max_speed_crad_s) / 100.0,
    }
}

/// A max acceleration in rad/s² as the 0.01 rad/s² field of 0x475.
pub(crate) fn max_acc_field(max_acc_rad_s2: f64) -> Result<u16, RangeError> {
    keep_or_u16("max_acc_rad_s2", Some(max_acc_rad_s2), 100.0)
}

/// The 0.01 rad/s² field of 0x47C in rad/s².
pub(crate) fn max_acc(crad_s2: u16) -> f64 {
    f64::from(crad_s2) / 100.0
}

/// An end-limit change as 0x479.
pub(crate) fn end_params_set(update: &EndLimitsUpdate) -> Result<EndParams, RangeError> {
    Ok(EndParams {
        lin_vel_mm_s: keep_or_u16("linear_m_s", update.linear_m_s, 1000.0)?,
        ang_vel_mrad_s: keep_or_u16("angular_rad_s", update.angular_rad_s, 1000.0)?,
        lin_acc_mm_s2: keep_or_u16("linear_acc_m_s2", update.linear_acc_m_s2, 1000.0)?,
        ang_acc_mrad_s2: keep_or_u16("angular_acc_rad_s2", update.angular_acc_rad_s2, 1000.0)?,
    })
}

/// A 0x478 reply in SI units.
pub(crate) fn end_limits(wire: &EndParams) -> EndLimits {
    let si = |v: u16| f64::from(v) / 1000.0;
    EndLimits {
        linear_m_s: si(wire.lin_vel_mm_s),
        angular_rad_s: si(wire.ang_vel_mrad_s),
        linear_acc_m_s2: si(wire.lin_acc_mm_s2),
        angular_acc_rad_s2: si(wire.ang_acc_mrad_s2),
    }
}

/// Collision levels (0–8, `None` = keep) as 0x47A.
pub(crate) fn collision_set(levels: [Option<u8>; 6]) -> Result<CollisionLevels, RangeError> {
    let mut out = [0xFF; 6];
    for (slot, level) in out.iter_mut().zip(levels) {
        match level {
            None => {}
            Some(level @ 0..=8) => *slot = level,
            Some(level) => {
                return Err(RangeError {
                    field: "collision level",
                    value: f64::from(level),
                })
            }
        }
    }
    Ok(CollisionLevels { levels: out })
}

/// A 0x47E reply in SI units.
pub(crate) fn gripper_teach(wire: &WireGripperTeach) -> GripperTeachParams {
    GripperTeachParams {
        teach_coefficient_pct: wire.teach_coef_pct,
        max_stroke_m: f64::from(wire.max_stroke_mm) / 1000.0,
        friction: wire.friction,
    }
}

/// `update` applied over the arm's `current` parameters, as 0x47D.
pub(crate) fn gripper_teach_set(
    current: &WireGripperTeach,
    update: &GripperTeachUpdate,
) -> Result<WireGripperTeach, RangeError> {
    let max_stroke_mm = match update.max_stroke_m {
        None => current.max_stroke_mm,
        Some(m) => {
            let mm = (m * 1000.0).round();
            if !(mm.is_finite() && (0.0..=255.0).contains(&mm)) {
                return Err(RangeError {
                    field: "max_stroke_m",
                    value: m,
                });
            }
            mm as u8
        }
    };
    Ok(WireGripperTeach {
        teach_coef_pct: update
            .teach_coefficient_pct
            .unwrap_or(current.teach_coef_pct),
        max_stroke_mm,
        friction: update.friction.unwrap_or(current.friction),
    })
}

/// The payload code of 0x477.
pub(crate) fn payload(payload: EndPayload) -> Payload {
    match payload {
        EndPayload::Empty => Payload::Empty,
        EndPayload::Half => Payload::Half,
        EndPayload::Full => Payload::Full,
    }
}

/// The linkage code of 0x470 (`None`: no change of role).
pub(crate) fn linkage(role: Option<ArmRole>) -> LinkageConfig {
    match role {
        None => LinkageConfig::None,
        Some(ArmRole::Leader) => LinkageConfig::Leader,
        Some(ArmRole::Follower) => LinkageConfig::Follower,
    }
}

/// The id-offset code of 0x470.
pub(crate) fn id_offset(shift: IdShift) -> IdOffset {
    match shift {
        IdShift::None => IdOffset::None,
        IdShift::Plus10 => IdOffset::Plus10,
        IdShift::Plus20 => IdOffset::Plus20,
    }
}

/// A 0x2A1 frame, typed.
pub(crate) fn arm_status(wire: &WireArmStatus) -> ArmStatus {
    ArmStatus {
        ctrl_mode: wire.ctrl_mode,
        status: wire.arm_status,
        // The arm never reports "unchanged"; should it, the raw code is kept.
        move_mode: active_move(wire.mode_feed)
            .unwrap_or(ActiveMove::Unknown(u8::from(wire.mode_feed))),
        teach: wire.teach_status,
        motion: wire.motion_status,
        trajectory_point: wire.trajectory_num,
        angle_limit_exceeded: wire.angle_limit_exceeded,
        comm_error: wire.comm_error,
    }
}

/// A 0x2A8 frame in SI units.
pub(crate) fn gripper_state(wire: &GripperFeedback) -> GripperState {
    GripperState {
        stroke_m: um_to_m(wire.stroke_um),
        torque_nm: f64::from(wire.torque_mnm) * 1e-3,
        status: wire.status,
    }
}

/// A 0x251–0x256 frame in SI units.
pub(crate) fn motor_state(wire: &HighSpeedFeedback) -> MotorState {
    MotorState {
        joint: wire.joint,
        speed_rad_s: f64::from(wire.speed_mrad_s) * 1e-3,
        current_a: f64::from(wire.current_ma) * 1e-3,
        position_rad: f64::from(wire.position_mrad) * 1e-3,
        effort_nm: wire.effort_mnm() * 1e-3,
    }
}

/// A 0x261–0x266 frame in SI units.
pub(crate) fn driver_state(wire: &LowSpeedFeedback) -> DriverState {
    DriverState {
        joint: wire.joint,
        bus_voltage_v: f64::from(wire.bus_voltage_dv) / 10.0,
        driver_temp_c: f64::from(wire.driver_temp_c),
        motor_temp_c: f64::from(wire.motor_temp_c),
        status: wire.status,
        bus_current_a: f64::from(wire.bus_current_ma) * 1e-3,
    }
}

/// A 0x481–0x486 frame in SI units.
pub(crate) fn end_motion(wire: &EndVelAccFeedback) -> EndMotion {
    let si = |v: u16| f64::from(v) / 1000.0;
    EndMotion {
        joint: wire.joint,
        linear_m_s: si(wire.lin_vel_mm_s),
        angular_rad_s: si(wire.ang_vel_mrad_s),
        linear_acc_m_s2: si(wire.lin_acc_mm_s2),
        angular_acc_rad_s2: si(wire.ang_acc_mrad_s2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keep_fields_send_the_unchanged_code_and_values_scale() {
        let update = JointLimitsUpdate {
            min_rad: None,
            max_rad: Some(120f64.to_radians()),
            max_speed_rad_s: Some(2.5),
        };
        let wire = joint_limits_set(1, &update).expect("in range");
        assert_eq!(
            (
                wire.min_angle_ddeg,
                wire.max_angle_ddeg,
                wire.max_speed_crad_s
            ),
            (0x7FFF, 1200, 250)
        );
        let back = joint_limits(&wire);
        assert!((back.max_rad - 120f64.to_radians()).abs() < 1e-12);
        assert_eq!(back.max_speed_rad_s, 2.5);
        let too_fast = JointLimitsUpdate {
            max_speed_rad_s: Some(400.0),
            ..JointLimitsUpdate::default()
        };
        assert_eq!(
            joint_limits_set(1, &too_fast).map(|_| ()),
            Err(RangeError {
                field: "max_speed_rad_s",
                value: 400.0
            })
        );
        let end = end_params_set(&EndLimitsUpdate {
            linear_m_s: Some(0.5),
            ..EndLimitsUpdate::default()
        })
        .expect("in range");
        assert_eq!((end.lin_vel_mm_s, end.ang_vel_mrad_s), (500, 0x7FFF));
        assert!(end_params_set(&EndLimitsUpdate {
            angular_rad_s: Some(-0.1),
            ..EndLimitsUpdate::default()
        })
        .is_err());
        let levels = collision_set([Some(1), None, Some(8), None, None, Some(0)]).expect("ok");
        assert_eq!(levels.levels, [1, 0xFF, 8, 0xFF, 0xFF, 0]);
        assert!(collision_set([Some(9), None, None, None, None, None]).is_err());
    }

    #[test]
    fn mit_codes_follow_the_firmware_and_report_as_one_mode() {
        let old = move_code(MoveKind::Mit, Some(FirmwareVersion::new(1, 8, 7)));
        let new = move_code(MoveKind::Mit, Some(FirmwareVersion::new(1, 8, 8)));
        assert_eq!(old, (MoveMode::Mit, MitMode::Mit));
        assert_eq!(new, (MoveMode::MitV188, MitMode::Mit));
        assert_eq!(active_move(old.0), Some(ActiveMove::Mit));
        assert_eq!(active_move(new.0), Some(ActiveMove::Mit));
        assert_eq!(active_move(MoveMode::Unchanged), None);
        assert_eq!(
            move_code(MoveKind::HighFollow, None),
            (MoveMode::J, MitMode::Mit)
        );
    }

    #[test]
    fn gripper_teach_updates_merge_over_the_current_values() {
        let current = WireGripperTeach {
            teach_coef_pct: 100,
            max_stroke_mm: 70,
            friction: 1,
        };
        let update = GripperTeachUpdate {
            max_stroke_m: Some(0.1),
            friction: Some(5),
            ..GripperTeachUpdate::default()
        };
        let merged = gripper_teach_set(&current, &update).expect("in range");
        assert_eq!(
            (merged.teach_coef_pct, merged.max_stroke_mm, merged.friction),
            (100, 100, 5)
        );
        let huge = GripperTeachUpdate {
            max_stroke_m: Some(0.3),
            ..GripperTeachUpdate::default()
        };
        assert!(gripper_teach_set(&current, &huge).is_err());
        assert_eq!(gripper_teach(&merged).max_stroke_m, 0.1);
    }
}
