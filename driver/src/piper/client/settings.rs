//! Configuration commands (0x470–0x47D, 0x487, 0x121, CPV), acknowledged where the arm
//! acknowledges. Arguments are SI or typed; `None` fields keep the arm's value.

use std::sync::atomic::Ordering;

use super::commands::check_joint;
use super::Piper;
use crate::piper::codec::si;
use crate::piper::codec::{
    AckedCommand, AssistLevels, CpvFrame, CpvMode, JointConfig, LeaderFollowerConfig, LeaderHome,
    LedCtrl, ParamCommand, ParamReset, UNCHANGED_U16,
};
use crate::piper::error::PiperError;
use crate::piper::types::{
    ArmRole, EndLimitsUpdate, EndPayload, GripperTeachUpdate, JointLimitsUpdate, JointSelect,
    RoleOffsets,
};

fn check_select(select: JointSelect) -> Result<(), PiperError> {
    match select {
        JointSelect::Joint(joint) => check_joint(joint).map(|_| ()),
        JointSelect::All => Ok(()),
    }
}

impl Piper {
    /// Leader/follower configuration (0x470; no reply exists). `role: None` changes only the
    /// id offsets.
    pub async fn set_role(
        &self,
        role: Option<ArmRole>,
        offsets: RoleOffsets,
    ) -> Result<(), PiperError> {
        let config = LeaderFollowerConfig {
            linkage: si::linkage(role),
            feedback_offset: si::id_offset(offsets.feedback),
            ctrl_offset: si::id_offset(offsets.control),
            target_offset: si::id_offset(offsets.target),
        };
        self.send_frame(config.encode()).await
    }

    /// Leader-arm homing (0x191, fw >= V1.7-4).
    pub async fn leader_home(&self, request: LeaderHome) -> Result<(), PiperError> {
        self.send_frame(request.encode()).await
    }

    /// Change a joint's angle limits (rad) and max speed (rad/s), acked (0x474 → 0x476).
    pub async fn set_joint_limits(
        &self,
        joint: u8,
        update: JointLimitsUpdate,
    ) -> Result<(), PiperError> {
        check_joint(joint)?;
        let limits = si::joint_limits_set(joint, &update)?;
        self.send_acked(limits.encode_set(), AckedCommand::SetJointLimits)
            .await
            .map(|_| ())
    }

    /// Set a joint's max speed (rad/s) only, acked.
    pub async fn set_joint_max_speed(
        &self,
        joint: u8,
        max_speed_rad_s: f64,
    ) -> Result<(), PiperError> {
        let update = JointLimitsUpdate {
            max_speed_rad_s: Some(max_speed_rad_s),
            ..JointLimitsUpdate::default()
        };
        self.set_joint_limits(joint, update).await
    }

    /// Set the max speed (rad/s) of all six joints, acked one by one.
    pub async fn set_max_speed_all(&self, max_speed_rad_s: f64) -> Result<(), PiperError> {
        for joint in 1..=6 {
            self.set_joint_max_speed(joint, max_speed_rad_s).await?;
        }
        Ok(())
    }

    /// Send a 0x475 joint configuration, acked (a failed zero-set is [`PiperError::Rejected`]).
    async fn joint_config(&self, config: JointConfig) -> Result<(), PiperError> {
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

    /// Set the current position of the selected joints as their zero, acked.
    pub async fn set_joint_zero(&self, joints: JointSelect) -> Result<(), PiperError> {
        check_select(joints)?;
        self.joint_config(JointConfig {
            joint: si::joint_select(joints),
            set_zero: true,
            apply_acc: false,
            max_acc_crad_s2: UNCHANGED_U16,
            clear_error: false,
        })
        .await
    }

    /// Set the max acceleration (rad/s², 0–5) of the selected joints, acked.
    pub async fn set_joint_max_acc(
        &self,
        joints: JointSelect,
        max_acc_rad_s2: f64,
    ) -> Result<(), PiperError> {
        check_select(joints)?;
        self.joint_config(JointConfig {
            joint: si::joint_select(joints),
            set_zero: false,
            apply_acc: true,
            max_acc_crad_s2: si::max_acc_field(max_acc_rad_s2)?,
            clear_error: false,
        })
        .await
    }

    /// Clear the error of the selected joints, acked.
    pub async fn clear_joint_error(&self, joints: JointSelect) -> Result<(), PiperError> {
        check_select(joints)?;
        self.joint_config(JointConfig {
            joint: si::joint_select(joints),
            set_zero: false,
            apply_acc: false,
            max_acc_crad_s2: UNCHANGED_U16,
            clear_error: true,
        })
        .await
    }

    async fn param_settings(&self, command: ParamCommand) -> Result<(), PiperError> {
        self.send_acked(command.encode(), AckedCommand::ParamSettings)
            .await
            .map(|_| ())
    }

    /// Reset all joint limits, max speeds and accelerations to the defaults (0x477), acked.
    pub async fn reset_joint_params(&self) -> Result<(), PiperError> {
        self.param_settings(ParamCommand {
            reset: Some(ParamReset::JointParams),
            ..ParamCommand::default()
        })
        .await
    }

    /// Reset the end-effector velocity / acceleration limits to the defaults (0x477), acked.
    pub async fn reset_end_limits(&self) -> Result<(), PiperError> {
        self.param_settings(ParamCommand {
            reset: Some(ParamReset::EndParams),
            ..ParamCommand::default()
        })
        .await
    }

    /// Switch the periodic 0x481–0x486 end velocity / acceleration feedback on or off, acked.
    pub async fn set_end_motion_feedback(&self, on: bool) -> Result<(), PiperError> {
        self.param_settings(ParamCommand {
            feedback_48x: Some(on),
            ..ParamCommand::default()
        })
        .await
    }

    /// Set the end-effector payload (0x477), acked.
    pub async fn set_payload(&self, payload: EndPayload) -> Result<(), PiperError> {
        self.param_settings(ParamCommand {
            payload: Some(si::payload(payload)),
            ..ParamCommand::default()
        })
        .await
    }

    /// Change the end-effector velocity / acceleration limits (m/s, rad/s, m/s², rad/s²),
    /// acked (0x479 → 0x476).
    pub async fn set_end_limits(&self, update: EndLimitsUpdate) -> Result<(), PiperError> {
        let params = si::end_params_set(&update)?;
        self.send_acked(params.encode_set(), AckedCommand::SetEndParams)
            .await
            .map(|_| ())
    }

    /// Set collision-protection levels 0–8 per joint (`None` keeps a joint's level), acked.
    pub async fn set_collision_levels(&self, levels: [Option<u8>; 6]) -> Result<(), PiperError> {
        let levels = si::collision_set(levels)?;
        self.send_acked(levels.encode_set(), AckedCommand::SetCollision)
            .await
            .map(|_| ())
    }

    /// Change the gripper / teach-pendant parameters (0x47D; the arm sends no ack). The frame
    /// has no "keep" code, so the driver reads the current values first (0x477 → 0x47E) and
    /// sends them back for the fields left `None`.
    pub async fn set_gripper_teach_params(
        &self,
        update: GripperTeachUpdate,
    ) -> Result<(), PiperError> {
        let current = self.query_gripper_teach_wire().await?;
        let params = si::gripper_teach_set(&current, &update)?;
        self.send_frame(params.encode_set()).await
    }

    /// Set joint assistance levels (0x487, \[AGX\] only; meaning undocumented, no ack).
    pub async fn set_assist_levels(&self, levels: [u8; 6]) -> Result<(), PiperError> {
        self.send_frame(AssistLevels { levels }.encode_set()).await
    }

    /// LED colour of joint 1–6 (0x121, documented only in \[DOC\]): one LED (`Some(index)`,
    /// 0–254) or all of them (`None`).
    pub async fn set_led(
        &self,
        joint: u8,
        led: Option<u8>,
        rgb: [u8; 3],
    ) -> Result<(), PiperError> {
        check_joint(joint)?;
        if led == Some(0xFF) {
            return Err(PiperError::InvalidValue {
                field: "led",
                value: 255.0,
            });
        }
        let counter = self.inner.led_counter.fetch_add(1, Ordering::Relaxed);
        let command = LedCtrl {
            enable: true,
            joint,
            led: led.unwrap_or(0xFF),
            rgb,
            counter,
        };
        self.send_frame(command.encode()).await
    }

    /// Write a CPV parameter of motor 1–7 (0x180 + motor; no documented ack). CPV
    /// parameters are undocumented vendor registers: the value is passed through as is.
    pub async fn cpv_write(&self, motor: u8, param: [u8; 2], value: i32) -> Result<(), PiperError> {
        if !(1..=7).contains(&motor) {
            return Err(PiperError::InvalidJoint { joint: motor });
        }
        let frame = CpvFrame {
            motor,
            mode: CpvMode::Write,
            param,
            value,
        };
        self.send_frame(frame.encode()).await
    }
}
