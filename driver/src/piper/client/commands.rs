//! Commands (seed interface V2): motion, mode, enable with confirmation, gripper, MIT, config.

use std::time::Duration;

use tokio::time::{sleep_until, Instant};

use super::{lock, Piper};
use crate::piper::codec::FirmwareVersion;
use crate::piper::codec::{
    encode_motor_enable, encode_move_c_point, AckedCommand, AssistLevels, CollisionLevels,
    CpvFrame, CtrlMode, EmergencyStop, EndParams, EndPoseTarget, GripperCtrl, GripperTeachParams,
    InstallPosition, JointConfig, JointLimits, JointMask, JointTargets, LeaderFollowerConfig,
    LeaderHome, LedCtrl, MitCommand, MitMode, ModeCtrl, MotionCtrl1, MotionStatus, MotorSelect,
    MoveCPoint, MoveMode, ParamCommand, UNCHANGED_U16,
};
use crate::piper::error::PiperError;
use crate::piper::state::{mdeg_to_rad, rad_to_mdeg, PiperState};

/// A MOVE mode as the caller means it; the driver picks the firmware's wire code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveKind {
    /// MOVE P (Cartesian point to point, firmware IK).
    P,
    /// MOVE J (joint space, smoothed).
    J,
    /// MOVE L (linear).
    L,
    /// MOVE C (circular, points via [`Piper::move_c_point`]).
    C,
    /// MIT pass-through (0x04, or 0x06 from S-V1.8-8), with the 0xAD flag.
    Mit,
    /// MOVE CPV.
    Cpv,
    /// "High-follow": joint targets passed through without smoothing (MOVE J + 0xAD).
    HighFollow,
}

/// A gripper command in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripperCommand {
    /// Target stroke (jaw opening), m.
    pub stroke_m: f64,
    /// Torque limit, N·m (0–5 in the SDK).
    pub effort_nm: f64,
    /// Enable the gripper driver.
    pub enable: bool,
    /// Clear the gripper error.
    pub clear_error: bool,
}

fn check_joint(joint: u8) -> Result<u8, PiperError> {
    if (1..=6).contains(&joint) {
        Ok(joint)
    } else {
        Err(PiperError::InvalidJoint { joint })
    }
}

/// Undo the firmware's MIT quirks (spec §10) so the joint executes `command` as meant.
pub(crate) fn compensate_mit(
    command: MitCommand,
    joint: u8,
    version: FirmwareVersion,
) -> MitCommand {
    let mut out = command;
    if version.mit_sign_flipped() && matches!(joint, 1 | 2 | 4 | 6) {
        out.p_rad = -out.p_rad;
        out.v_rad_s = -out.v_rad_s;
        out.t_nm = -out.t_nm;
    }
    if version.mit_torque_x4_j123() && joint <= 3 {
        out.t_nm /= 4.0;
    }
    out
}

fn check_speed(speed_pct: u8) -> Result<u8, PiperError> {
    if speed_pct <= 100 {
        Ok(speed_pct)
    } else {
        Err(PiperError::InvalidValue {
            field: "speed_pct",
            value: f64::from(speed_pct),
        })
    }
}

impl Piper {
    /// Quick stop (0x150 `01`): motors go to damping.
    pub async fn emergency_stop(&self) -> Result<(), PiperError> {
        self.send_frame(MotionCtrl1::estop(EmergencyStop::Stop).encode())
            .await
    }

    /// Resume after a quick stop (0x150 `02`).
    pub async fn resume(&self) -> Result<(), PiperError> {
        self.send_frame(MotionCtrl1::estop(EmergencyStop::Resume).encode())
            .await
    }

    /// Reset (the SDK's `ResetPiper`, 0x150 `02`): clears errors, motors end disabled and the
    /// arm returns to standby; also the way out of MIT and teach mode.
    pub async fn reset(&self) -> Result<(), PiperError> {
        self.resume().await
    }

    /// Any 0x150 command (offline trajectory, drag teach).
    pub async fn motion_ctrl_1(&self, command: MotionCtrl1) -> Result<(), PiperError> {
        self.send_frame(command.encode()).await
    }

    /// Any 0x151 mode command, as given.
    pub async fn mode_ctrl(&self, command: ModeCtrl) -> Result<(), PiperError> {
        check_speed(command.speed_pct)?;
        self.send_frame(command.encode()).await
    }

    /// CAN-command mode with `kind` at `speed_pct` (0–100).
    pub async fn set_move_mode(&self, kind: MoveKind, speed_pct: u8) -> Result<(), PiperError> {
        let (move_mode, mit_mode) = self.move_mode_code(kind);
        self.mode_ctrl(ModeCtrl {
            ctrl_mode: CtrlMode::CanCommand,
            move_mode,
            speed_pct: check_speed(speed_pct)?,
            mit_mode,
            dwell_s: 0,
            install_pos: InstallPosition::Unchanged,
        })
        .await
    }

    /// Set the installation position (fw >= V1.5-2) without changing the move mode.
    pub async fn set_install_position(&self, position: InstallPosition) -> Result<(), PiperError> {
        self.mode_ctrl(ModeCtrl {
            ctrl_mode: CtrlMode::CanCommand,
            move_mode: MoveMode::Unchanged,
            speed_pct: 0,
            mit_mode: MitMode::Ignore,
            dwell_s: 0,
            install_pos: position,
        })
        .await
    }

    /// The wire MOVE-mode code and MIT flag of `kind` for the firmware in use.
    pub fn move_mode_code(&self, kind: MoveKind) -> (MoveMode, MitMode) {
        match kind {
            MoveKind::P => (MoveMode::P, MitMode::PositionVelocity),
            MoveKind::J => (MoveMode::J, MitMode::PositionVelocity),
            MoveKind::L => (MoveMode::L, MitMode::PositionVelocity),
            MoveKind::C => (MoveMode::C, MitMode::PositionVelocity),
            MoveKind::Cpv => (MoveMode::Cpv, MitMode::PositionVelocity),
            MoveKind::HighFollow => (MoveMode::J, MitMode::Mit),
            MoveKind::Mit => {
                let code = self
                    .firmware_version()
                    .map_or(MoveMode::Mit, |v| v.mit_move_mode());
                (code, MitMode::Mit)
            }
        }
    }

    /// Wait until 0x2A1 reports CAN-command mode with the MOVE mode of `kind`.
    pub async fn wait_for_move_mode(
        &self,
        kind: MoveKind,
        timeout: Duration,
    ) -> Result<PiperState, PiperError> {
        let (code, _) = self.move_mode_code(kind);
        self.wait_for(
            move |s| {
                s.arm_status.as_ref().is_some_and(|a| {
                    a.value.ctrl_mode == CtrlMode::CanCommand && a.value.mode_feed == code
                })
            },
            timeout,
            "mode echo on 0x2A1",
        )
        .await
    }

    /// Enable motors and wait until the 0x261–0x266 enable bits confirm it (resending the
    /// command every retry interval, debounced over consecutive frames).
    pub async fn enable(&self, motor: MotorSelect) -> Result<(), PiperError> {
        self.set_enabled(motor, true).await
    }

    /// Disable motors (the arm falls!) and wait for the enable bits to clear.
    pub async fn disable(&self, motor: MotorSelect) -> Result<(), PiperError> {
        self.set_enabled(motor, false).await
    }

    async fn set_enabled(&self, motor: MotorSelect, enable: bool) -> Result<(), PiperError> {
        if let MotorSelect::Joint(joint) = motor {
            check_joint(joint)?;
        }
        let wanted = motor.joints();
        let timeouts = self.inner.config.timeouts;
        let debounce = self.inner.config.enable_debounce;
        let mut rx = self.subscribe_state();
        let start = Instant::now();
        let deadline = start + timeouts.enable;
        // Only frames received after the command count.
        let mut last_seq = rx.borrow().low_speed.map(|slot| slot.map_or(0, |s| s.seq));
        let mut streak = [0u32; 6];
        let frame = encode_motor_enable(motor, enable);
        self.send_frame(frame).await?;
        let mut next_retry = start + timeouts.enable_retry;
        loop {
            tokio::select! {
                changed = rx.changed() => {
                    if changed.is_err() {
                        return Err(PiperError::Disconnected);
                    }
                    let state = rx.borrow_and_update();
                    for joint in wanted.joints() {
                        let i = usize::from(joint - 1);
                        if let Some(low) = &state.low_speed[i] {
                            if low.seq != last_seq[i] {
                                last_seq[i] = low.seq;
                                streak[i] = if low.value.status.enabled() == enable { streak[i] + 1 } else { 0 };
                            }
                        }
                    }
                    if wanted.joints().iter().all(|j| streak[usize::from(j - 1)] >= debounce) {
                        tracing::debug!(?motor, enable, "enable state confirmed");
                        return Ok(());
                    }
                }
                _ = sleep_until(next_retry) => {
                    self.send_frame(frame).await?;
                    next_retry += timeouts.enable_retry;
                }
                _ = sleep_until(deadline) => {
                    let mut confirmed = 0u8;
                    for joint in wanted.joints() {
                        if streak[usize::from(joint - 1)] >= debounce {
                            confirmed |= 1 << (joint - 1);
                        }
                    }
                    return Err(PiperError::EnableTimeout {
                        enable,
                        wanted,
                        confirmed: JointMask(confirmed),
                        waited: timeouts.enable,
                    });
                }
            }
        }
    }

    /// Send the end-pose target frames 0x152–0x154 as given.
    pub async fn end_pose(&self, target: EndPoseTarget) -> Result<(), PiperError> {
        self.send_frames(&target.encode()).await
    }

    /// Send joint targets (0x155–0x157) in millidegrees, after the client-side limits.
    pub async fn joints_mdeg(&self, angles_mdeg: [i32; 6]) -> Result<(), PiperError> {
        self.joints_rad(angles_mdeg.map(mdeg_to_rad)).await
    }

    /// Send joint targets in rad, after the client-side limits (clamp or reject).
    pub async fn joints_rad(&self, targets_rad: [f64; 6]) -> Result<(), PiperError> {
        let config = &self.inner.config;
        let checked = config
            .limits
            .check_joints(targets_rad, config.joint_limit_policy)?;
        let angles_mdeg = checked.map(rad_to_mdeg);
        *lock(&self.inner.last_joint_target_mdeg) = Some(angles_mdeg);
        self.send_frames(&JointTargets { angles_mdeg }.encode())
            .await
    }

    /// MOVE J: CAN mode + MOVE J at `speed_pct`, then the joint targets (rad).
    pub async fn move_joints_rad(
        &self,
        targets_rad: [f64; 6],
        speed_pct: u8,
    ) -> Result<(), PiperError> {
        let config = &self.inner.config;
        // Check before sending anything, so a rejected target leaves the mode untouched.
        config
            .limits
            .check_joints(targets_rad, config.joint_limit_policy)?;
        self.set_move_mode(MoveKind::J, speed_pct).await?;
        self.joints_rad(targets_rad).await
    }

    /// Wait until 0x2A1 reports the target reached and every joint is within `tolerance_rad`
    /// of the last joint target sent.
    pub async fn wait_for_arrival(
        &self,
        tolerance_rad: f64,
        timeout: Duration,
    ) -> Result<PiperState, PiperError> {
        let target = *lock(&self.inner.last_joint_target_mdeg);
        self.wait_for(
            move |s| {
                let reached = s
                    .arm_status
                    .as_ref()
                    .is_some_and(|a| a.value.motion_status == MotionStatus::Reached);
                let close = match (target, s.joints_rad()) {
                    (Some(target), Some(now)) => target
                        .iter()
                        .zip(now.iter())
                        .all(|(t, n)| (mdeg_to_rad(*t) - n).abs() <= tolerance_rad),
                    (None, _) => true,
                    (Some(_), None) => false,
                };
                reached && close
            },
            timeout,
            "arrival at the joint target",
        )
        .await
    }

    /// MOVE C point index (0x158), sent after the pose of that point.
    pub async fn move_c_point(&self, point: MoveCPoint) -> Result<(), PiperError> {
        self.send_frame(encode_move_c_point(point)).await
    }

    /// Gripper command in SI units, after the client-side gripper limit.
    pub async fn gripper(&self, command: GripperCommand) -> Result<(), PiperError> {
        let config = &self.inner.config;
        let stroke_m = config
            .limits
            .check_gripper(command.stroke_m, config.gripper_limit_policy)?;
        if !(0.0..=65.535).contains(&command.effort_nm) {
            return Err(PiperError::InvalidValue {
                field: "effort_nm",
                value: command.effort_nm,
            });
        }
        self.gripper_ctrl(GripperCtrl {
            stroke_um: (stroke_m * 1e6).round() as i32,
            effort_mnm: (command.effort_nm * 1000.0).round() as u16,
            enable: command.enable,
            clear_error: command.clear_error,
            set_zero: false,
        })
        .await
    }

    /// Raw 0x159 gripper control.
    pub async fn gripper_ctrl(&self, command: GripperCtrl) -> Result<(), PiperError> {
        self.send_frame(command.encode()).await
    }

    /// Set the gripper's current position as zero (sent with the gripper disabled, spec §5.6).
    pub async fn gripper_set_zero(&self) -> Result<(), PiperError> {
        self.gripper_ctrl(GripperCtrl {
            stroke_um: 0,
            effort_mnm: 0,
            enable: false,
            clear_error: false,
            set_zero: true,
        })
        .await
    }

    /// MIT command for joint 1–6 (SI units), packed for the firmware in use. The MIT mode must
    /// be selected first ([`MoveKind::Mit`]).
    pub async fn mit(&self, joint: u8, command: MitCommand) -> Result<(), PiperError> {
        check_joint(joint)?;
        for (field, value) in [
            ("p_rad", command.p_rad),
            ("v_rad_s", command.v_rad_s),
            ("kp", command.kp),
            ("kd", command.kd),
            ("t_nm", command.t_nm),
        ] {
            if !value.is_finite() {
                return Err(PiperError::InvalidValue { field, value });
            }
        }
        let packing = self.mit_packing();
        let command = match self.firmware_version() {
            Some(version) if self.inner.config.mit_quirks => {
                compensate_mit(command, joint, version)
            }
            _ => command,
        };
        self.send_frame(command.quantise(packing).encode(joint, packing))
            .await
    }

    /// Leader/follower configuration (0x470; no reply exists).
    pub async fn set_leader_follower(
        &self,
        config: LeaderFollowerConfig,
    ) -> Result<(), PiperError> {
        self.send_frame(config.encode()).await
    }

    /// Leader-arm homing (0x191, fw >= V1.7-4).
    pub async fn leader_home(&self, request: LeaderHome) -> Result<(), PiperError> {
        self.send_frame(request.encode()).await
    }

    /// Set a joint's angle limits and max speed (0x474) and wait for the 0x476 ack.
    pub async fn set_joint_limits(&self, limits: JointLimits) -> Result<(), PiperError> {
        check_joint(limits.joint)?;
        self.send_acked(limits.encode_set(), AckedCommand::SetJointLimits)
            .await
            .map(|_| ())
    }

    /// Set a joint's max speed only (angles unchanged), 0.01 rad/s, acked.
    pub async fn set_joint_max_speed(
        &self,
        joint: u8,
        max_speed_crad_s: u16,
    ) -> Result<(), PiperError> {
        let unchanged = UNCHANGED_U16 as i16;
        self.set_joint_limits(JointLimits {
            joint,
            max_angle_ddeg: unchanged,
            min_angle_ddeg: unchanged,
            max_speed_crad_s,
        })
        .await
    }

    /// Set the max speed of all six joints, acked one by one.
    pub async fn set_max_speed_all(&self, max_speed_crad_s: u16) -> Result<(), PiperError> {
        for joint in 1..=6 {
            self.set_joint_max_speed(joint, max_speed_crad_s).await?;
        }
        Ok(())
    }

    /// Raw 0x475 joint configuration, acked (a failed zero-set is [`PiperError::Rejected`]).
    pub async fn joint_config(&self, config: JointConfig) -> Result<(), PiperError> {
        if config.joint != 7 {
            check_joint(config.joint)?;
        }
        let ack = self
            .send_acked(config.encode(), AckedCommand::JointConfig)
            .await?;
        if config.set_zero && !ack.zero_ok {
            return Err(PiperError::Rejected {
                command: AckedCommand::JointConfig,
                reason: "zero not set",
            });
        }
        Ok(())
    }

    /// Set the current position of joint 1–6 (7 = all) as its zero.
    pub async fn set_joint_zero(&self, joint: u8) -> Result<(), PiperError> {
        self.joint_config(JointConfig {
            joint,
            set_zero: true,
            apply_acc: false,
            max_acc_crad_s2: UNCHANGED_U16,
            clear_error: false,
        })
        .await
    }

    /// Set the max acceleration of joint 1–6 (7 = all), 0.01 rad/s² (0–500).
    pub async fn set_joint_max_acc(
        &self,
        joint: u8,
        max_acc_crad_s2: u16,
    ) -> Result<(), PiperError> {
        self.joint_config(JointConfig {
            joint,
            set_zero: false,
            apply_acc: true,
            max_acc_crad_s2,
            clear_error: false,
        })
        .await
    }

    /// Clear the error of joint 1–6 (7 = all).
    pub async fn clear_joint_error(&self, joint: u8) -> Result<(), PiperError> {
        self.joint_config(JointConfig {
            joint,
            set_zero: false,
            apply_acc: false,
            max_acc_crad_s2: UNCHANGED_U16,
            clear_error: true,
        })
        .await
    }

    /// 0x477 settings (reset to defaults, 0x48X feedback switch, payload), acked. Queries go
    /// through the `query_*` methods.
    pub async fn param_settings(&self, command: ParamCommand) -> Result<(), PiperError> {
        let command = ParamCommand {
            query: None,
            ..command
        };
        if !command.expects_ack() {
            return Err(PiperError::InvalidValue {
                field: "param_settings (nothing to set)",
                value: 0.0,
            });
        }
        self.send_acked(command.encode(), AckedCommand::ParamSettings)
            .await
            .map(|_| ())
    }

    /// Set end-effector max velocity / acceleration (0x479; 0x7FFF fields unchanged), acked.
    pub async fn set_end_params(&self, params: EndParams) -> Result<(), PiperError> {
        self.send_acked(params.encode_set(), AckedCommand::SetEndParams)
            .await
            .map(|_| ())
    }

    /// Set collision-protection levels 0–8 per joint (0xFF = unchanged), acked.
    pub async fn set_collision_levels(&self, levels: CollisionLevels) -> Result<(), PiperError> {
        for level in levels.levels {
            if level > 8 && level != 0xFF {
                return Err(PiperError::InvalidValue {
                    field: "collision level",
                    value: f64::from(level),
                });
            }
        }
        self.send_acked(levels.encode_set(), AckedCommand::SetCollision)
            .await
            .map(|_| ())
    }

    /// Set gripper / teach-pendant parameters (0x47D; the arm sends no ack).
    pub async fn set_gripper_teach_params(
        &self,
        params: GripperTeachParams,
    ) -> Result<(), PiperError> {
        self.send_frame(params.encode_set()).await
    }

    /// Set joint assistance levels (0x487, [AGX] only; no ack).
    pub async fn set_assist_levels(&self, levels: AssistLevels) -> Result<(), PiperError> {
        self.send_frame(levels.encode_set()).await
    }

    /// LED control (0x121, documented only in [DOC]).
    pub async fn led(&self, command: LedCtrl) -> Result<(), PiperError> {
        check_joint(command.joint)?;
        self.send_frame(command.encode()).await
    }

    /// Write a CPV parameter (0x180 + motor; no documented ack).
    pub async fn cpv_write(&self, frame: CpvFrame) -> Result<(), PiperError> {
        if !(1..=7).contains(&frame.motor) {
            return Err(PiperError::InvalidJoint { joint: frame.motor });
        }
        self.send_frame(frame.encode()).await
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mit_quirks_follow_the_firmware_milestones() {
        let command = MitCommand {
            p_rad: 0.5,
            v_rad_s: 1.0,
            kp: 10.0,
            kd: 1.0,
            t_nm: 2.0,
        };
        let old = FirmwareVersion::new(1, 6, 3);
        let flipped = compensate_mit(command, 2, old);
        assert_eq!(
            (flipped.p_rad, flipped.v_rad_s, flipped.t_nm),
            (-0.5, -1.0, -0.5)
        );
        let j3 = compensate_mit(command, 3, old);
        assert_eq!((j3.p_rad, j3.t_nm), (0.5, 0.5));
        let j4 = compensate_mit(command, 4, FirmwareVersion::new(1, 8, 2));
        assert_eq!(j4, command);
        let new = FirmwareVersion::new(1, 8, 8);
        assert_eq!(compensate_mit(command, 1, new), command);
    }
}
