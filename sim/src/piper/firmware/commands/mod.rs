//! Host commands: what each frame does to the firmware state, and the replies it triggers.
//! [`Firmware::handle_frame`] decodes a frame and hands it to its family: `motion` (modes,
//! targets, enabling, stopping and planning; `path` its Cartesian geometry) or `settings`
//! (configuration and queries).

mod motion;
mod path;
mod settings;
#[cfg(test)]
mod tests;

use bus::CanFrame;

use super::Firmware;
use crate::piper::codec::host::{self, HostCommand};
use crate::piper::codec::DecodeError;

impl Firmware {
    /// Feed one frame from the bus. Frames that are not Piper host commands, or are malformed,
    /// are ignored as the firmware ignores them.
    pub fn handle_frame(&mut self, frame: &CanFrame) {
        let cmd = match host::decode(frame, u16::from(self.flash.control_offset), self.profile) {
            Ok(c) => c,
            Err(DecodeError::UnknownId { .. }) | Err(DecodeError::Extended { .. }) => return,
            Err(e) => {
                tracing::debug!(error = %e, frame = %frame, "Piper firmware ignored a frame");
                return;
            }
        };
        if self.silent && !matches!(cmd, HostCommand::UpgradeMode(_)) {
            return;
        }
        // A leader arm ignores motion commands (spec §6.1); configuration still works.
        let motion_cmd = matches!(
            cmd,
            HostCommand::ModeCtrl(_)
                | HostCommand::EndPose { .. }
                | HostCommand::Joint { .. }
                | HostCommand::MoveCPoint(_)
                | HostCommand::Gripper(_)
                | HostCommand::Mit { .. }
        );
        if self.leader_active && motion_cmd {
            return;
        }
        match cmd {
            HostCommand::Led { .. } | HostCommand::SetAssist(_) => {
                if let HostCommand::SetAssist(levels) = cmd {
                    self.flash.assist_levels = levels;
                    self.mark_flash_dirty();
                }
            }
            HostCommand::MotionCtrl1(m) => self.on_motion_ctrl_1(m),
            HostCommand::ModeCtrl(m) => self.on_mode_ctrl(m),
            HostCommand::EndPose {
                part,
                first,
                second,
            } => self.on_end_pose(part, first, second),
            HostCommand::Joint {
                pair,
                first_mdeg,
                second_mdeg,
            } => self.on_joint_pair(pair, first_mdeg, second_mdeg),
            HostCommand::MoveCPoint(p) => self.on_move_c_point(p),
            HostCommand::Gripper(g) => self.on_gripper(g),
            HostCommand::Mit { joint, cmd } => self.on_mit(joint, cmd),
            HostCommand::Cpv {
                motor,
                mode,
                param,
                value,
            } => self.on_cpv(motor, mode, param, value),
            HostCommand::LeaderHome { bytes } => self.on_leader_home(bytes),
            HostCommand::UpgradeMode(m) => self.silent = m != 0,
            HostCommand::Linkage(cfg) => self.on_linkage(cfg),
            HostCommand::MotorEnable { motor, enable } => self.on_motor_enable(motor, enable),
            HostCommand::JointQuery {
                joint,
                acceleration,
            } => self.on_joint_query(joint, acceleration),
            HostCommand::SetJointLimits {
                joint,
                max_angle_ddeg,
                min_angle_ddeg,
                max_speed_crad_s,
            } => self.on_set_joint_limits(joint, max_angle_ddeg, min_angle_ddeg, max_speed_crad_s),
            HostCommand::JointConfig {
                joint,
                set_zero,
                max_acc_crad_s2,
                clear_error,
            } => self.on_joint_config(joint, set_zero, max_acc_crad_s2, clear_error),
            HostCommand::ParamQuery(p) => self.on_param_query(p),
            HostCommand::SetEndVelAcc(e) => self.on_set_end_vel_acc(e),
            HostCommand::SetCollision(levels) => self.on_set_collision(levels),
            HostCommand::SetGripperTeach {
                travel_pct,
                max_stroke_mm,
                friction,
            } => self.on_set_gripper_teach(travel_pct, max_stroke_mm, friction),
            HostCommand::FirmwareQuery => self.on_firmware_query(),
        }
    }
}
