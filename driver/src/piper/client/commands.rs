//! Commands (seed interface V2): motion, mode, enable with confirmation, gripper, MIT. Every
//! argument is SI or typed; `codec::si` builds the frames.

use std::time::Duration;

use tokio::time::{sleep_until, Instant};

use super::{lock, Piper};
use crate::piper::codec::si::{self, RangeError};
use crate::piper::codec::{
    encode_motor_enable, encode_move_c_point, CtrlMode, EmergencyStop, FirmwareVersion,
    GripperCtrl, JointMask, MitCommand, MotionCtrl1, MotionStatus, MotorSelect, TeachStatus,
    TrackCommand,
};
use crate::piper::error::PiperError;
use crate::piper::state::PiperState;
use crate::piper::types::{CirclePoint, GripperCommand, Install, ModeCommand, MoveKind, Pose};

impl From<RangeError> for PiperError {
    fn from(error: RangeError) -> Self {
        PiperError::InvalidValue {
            field: error.field,
            value: error.value,
        }
    }
}

pub(crate) fn check_joint(joint: u8) -> Result<u8, PiperError> {
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

    /// Drag-teach command (0x150 byte 2: record, execute, pause, …).
    pub async fn drag_teach(&self, command: TeachStatus) -> Result<(), PiperError> {
        self.send_frame(
            MotionCtrl1 {
                drag_teach: command,
                ..MotionCtrl1::estop(EmergencyStop::None)
            }
            .encode(),
        )
        .await
    }

    /// Offline-trajectory command (0x150 byte 1: pause, continue, clear, …). Transfers go
    /// through [`Piper::trajectory_transfer_point`] and [`Piper::trajectory_transfer_end`].
    pub async fn trajectory_command(&self, command: TrackCommand) -> Result<(), PiperError> {
        self.send_frame(
            MotionCtrl1 {
                track: command,
                ..MotionCtrl1::estop(EmergencyStop::None)
            }
            .encode(),
        )
        .await
    }

    /// Mode command (0x151): control mode, MOVE mode (the driver picks the firmware's code),
    /// speed, MIT flag and installation position.
    pub async fn set_mode(&self, command: ModeCommand) -> Result<(), PiperError> {
        check_speed(command.speed_pct)?;
        let frame = si::mode_ctrl(&command, self.firmware_version()).encode();
        self.send_frame(frame).await
    }

    /// CAN-command mode with `kind` at `speed_pct` (0–100).
    pub async fn set_move_mode(&self, kind: MoveKind, speed_pct: u8) -> Result<(), PiperError> {
        self.set_mode(ModeCommand {
            control: CtrlMode::CanCommand,
            move_kind: kind,
            speed_pct,
            mit_flag: None,
            install: None,
        })
        .await
    }

    /// Set the installation position (fw >= V1.5-2) without changing the move mode.
    pub async fn set_install_position(&self, position: Install) -> Result<(), PiperError> {
        self.send_frame(si::install_only(position).encode()).await
    }

    /// Wait until 0x2A1 reports CAN-command mode with the MOVE mode of `kind` (MIT matches
    /// whichever code the firmware uses).
    pub async fn wait_for_move_mode(
        &self,
        kind: MoveKind,
        timeout: Duration,
    ) -> Result<PiperState, PiperError> {
        self.wait_for(
            move |s| {
                s.arm_status.as_ref().is_some_and(|a| {
                    a.value.ctrl_mode == CtrlMode::CanCommand && a.value.move_mode.matches(kind)
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

    /// Send a Cartesian target (0x152–0x154): position in m, ZYX Euler angles in rad.
    pub async fn end_pose(&self, target: Pose) -> Result<(), PiperError> {
        for (field, value) in target
            .position_m
            .iter()
            .chain(target.orientation_rad.iter())
            .map(|v| ("pose", *v))
        {
            if !value.is_finite() {
                return Err(PiperError::InvalidValue { field, value });
            }
        }
        self.send_frames(&si::end_pose_target(&target).encode())
            .await
    }

    /// Send joint targets in rad, after the client-side limits (clamp or reject).
    pub async fn joints_rad(&self, targets_rad: [f64; 6]) -> Result<(), PiperError> {
        let config = &self.inner.config;
        let checked = config
            .limits
            .check_joints(targets_rad, config.joint_limit_policy)?;
        *lock(&self.inner.last_joint_target_rad) = Some(checked);
        self.send_frames(&si::joint_targets(checked).encode()).await
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
        // Compare with what the wire carried (millidegree resolution), not the f64 asked for.
        let target = lock(&self.inner.last_joint_target_rad)
            .map(|t| t.map(|r| si::mdeg_to_rad(si::rad_to_mdeg(r))));
        self.wait_for(
            move |s| {
                let reached = s
                    .arm_status
                    .as_ref()
                    .is_some_and(|a| a.value.motion == MotionStatus::Reached);
                let close = match (target, s.joints_rad()) {
                    (Some(target), Some(now)) => target
                        .iter()
                        .zip(now.iter())
                        .all(|(t, n)| (t - n).abs() <= tolerance_rad),
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

    /// MOVE C point marker (0x158), sent after the pose of that point.
    pub async fn move_c_point(&self, point: CirclePoint) -> Result<(), PiperError> {
        self.send_frame(encode_move_c_point(si::circle_point(point)))
            .await
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
        let frame = si::gripper_ctrl(&GripperCommand {
            stroke_m,
            ..command
        })?;
        self.send_frame(frame.encode()).await
    }

    /// Set the gripper's current position as zero (sent with the gripper disabled, spec §5.6).
    pub async fn gripper_set_zero(&self) -> Result<(), PiperError> {
        let frame = GripperCtrl {
            stroke_um: 0,
            effort_mnm: 0,
            enable: false,
            clear_error: false,
            set_zero: true,
        };
        self.send_frame(frame.encode()).await
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
