//! The command families of the client, in SI units.

use super::RealmanClient;
use crate::realman::codec::decode::*;
use crate::realman::codec::request::{self as rq, CartesianTarget, DhRow, MoveOpts, PushSettings};
use crate::realman::codec::types::{Axis, Connect, Device, Direction, Pose, Smoothing};
use crate::realman::error::RealmanError;

/// Everything the connect handshake reads (the vendor SDK's 11 queries).
#[derive(Debug, Clone, PartialEq)]
pub struct Handshake {
    /// Product and versions.
    pub software: SoftwareInfo,
    /// Trajectory under way (`None` kind at rest).
    pub trajectory: CurrentTrajectory,
    /// Realtime push configuration.
    pub push: PushConfig,
    /// Current work frame.
    pub work_frame: WorkFrame,
    /// Current tool frame.
    pub tool_frame: ToolFrame,
    /// Mounting: rotation, pitch, azimuth (rad).
    pub install_pose_rad: [f64; 3],
    /// Lower joint limits, rad.
    pub joint_min_rad: Vec<f64>,
    /// Upper joint limits, rad.
    pub joint_max_rad: Vec<f64>,
    /// Joint acceleration limits, rad/s².
    pub joint_max_acc_rad_s2: Vec<f64>,
    /// Joint speed limits, rad/s.
    pub joint_max_speed_rad_s: Vec<f64>,
    /// DH table.
    pub dh: Vec<DhRow>,
}

/// Only moves that start execution produce an arrival event worth waiting for.
fn waits(o: &MoveOpts, block: bool) -> bool {
    block && o.connect == Connect::Start
}

impl RealmanClient {
    // ---- identity and handshake ----

    /// Runs the vendor SDK's connect handshake (11 queries, in its order).
    pub async fn handshake(&self) -> Result<Handshake, RealmanError> {
        Ok(Handshake {
            software: self.software_info().await?,
            trajectory: self.current_trajectory().await?,
            push: self.realtime_push().await?,
            work_frame: self.work_frame().await?,
            tool_frame: self.tool_frame().await?,
            install_pose_rad: self.install_pose().await?,
            joint_min_rad: self.joint_min_pos().await?,
            joint_max_rad: self.joint_max_pos().await?,
            joint_max_acc_rad_s2: self.joint_max_acc().await?,
            joint_max_speed_rad_s: self.joint_max_speed().await?,
            dh: self.dh_table().await?,
        })
    }

    /// `get_arm_software_info`: product (model, DOF) and versions.
    pub async fn software_info(&self) -> Result<SoftwareInfo, RealmanError> {
        self.query(rq::get_arm_software_info(), software_info).await
    }

    // ---- planned motion ----

    /// `movej` to `joints_rad`; with `block` (and [`Connect::Start`]) waits for arrival.
    pub async fn movej(
        &self,
        joints_rad: &[f64],
        o: MoveOpts,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(rq::movej(joints_rad, o)?, Device::Arm, waits(&o, block))
            .await
    }

    /// `movel` to `pose` in a straight line.
    pub async fn movel(&self, pose: &Pose, o: MoveOpts, block: bool) -> Result<(), RealmanError> {
        self.motion(rq::movel(pose, o)?, Device::Arm, waits(&o, block))
            .await
    }

    /// `movej_p`: joint-space move to `pose`.
    pub async fn movej_p(&self, pose: &Pose, o: MoveOpts, block: bool) -> Result<(), RealmanError> {
        self.motion(rq::movej_p(pose, o)?, Device::Arm, waits(&o, block))
            .await
    }

    /// `movec` through `via` to `to` with `loops` extra turns.
    pub async fn movec(
        &self,
        via: &Pose,
        to: &Pose,
        loops: u32,
        o: MoveOpts,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(rq::movec(via, to, loops, o)?, Device::Arm, waits(&o, block))
            .await
    }

    /// `moves`: one spline point (queue ≥ 3, the last with [`Connect::Start`]).
    pub async fn moves(&self, pose: &Pose, o: MoveOpts, block: bool) -> Result<(), RealmanError> {
        self.motion(rq::moves(pose, o)?, Device::Arm, waits(&o, block))
            .await
    }

    /// `set_joint_step`: step one joint (1-based) by `step_rad`.
    pub async fn joint_step(
        &self,
        joint: u8,
        step_rad: f64,
        speed_percent: u8,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(
            rq::set_joint_step(joint, step_rad, speed_percent)?,
            Device::Arm,
            block,
        )
        .await
    }

    /// `set_pos_step`: step the tool along `axis` by `step_m`.
    pub async fn pos_step(
        &self,
        axis: Axis,
        step_m: f64,
        speed_percent: u8,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(
            rq::set_pos_step(axis, step_m, speed_percent)?,
            Device::Arm,
            block,
        )
        .await
    }

    /// `set_ort_step`: rotate the tool about `axis` by `step_rad`.
    pub async fn ort_step(
        &self,
        axis: Axis,
        step_rad: f64,
        speed_percent: u8,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(
            rq::set_ort_step(axis, step_rad, speed_percent)?,
            Device::Arm,
            block,
        )
        .await
    }

    /// `set_joint_teach`: jog a joint until [`RealmanClient::stop_teach`].
    pub async fn joint_teach(
        &self,
        joint: u8,
        dir: Direction,
        speed_percent: u8,
    ) -> Result<(), RealmanError> {
        self.set(rq::set_joint_teach(joint, dir, speed_percent)?)
            .await
            .map(drop)
    }

    /// `set_pos_teach`: jog the tool position.
    pub async fn pos_teach(
        &self,
        axis: Axis,
        dir: Direction,
        speed_percent: u8,
    ) -> Result<(), RealmanError> {
        self.set(rq::set_pos_teach(axis, dir, speed_percent)?)
            .await
            .map(drop)
    }

    /// `set_ort_teach`: jog the tool orientation.
    pub async fn ort_teach(
        &self,
        axis: Axis,
        dir: Direction,
        speed_percent: u8,
    ) -> Result<(), RealmanError> {
        self.set(rq::set_ort_teach(axis, dir, speed_percent)?)
            .await
            .map(drop)
    }

    /// `set_stop_teach`: end a jog.
    pub async fn stop_teach(&self) -> Result<(), RealmanError> {
        self.set(rq::set_stop_teach()).await.map(drop)
    }

    // ---- passthrough (fire and forget) ----

    /// `movej_canfd`: stream a joint target (no reply).
    pub async fn movej_canfd(
        &self,
        joints_rad: &[f64],
        follow: bool,
        s: Smoothing,
    ) -> Result<(), RealmanError> {
        self.call(&rq::movej_canfd(joints_rad, follow, s)?)
            .await
            .map(drop)
    }

    /// `movep_canfd`: stream a Cartesian target (no reply).
    pub async fn movep_canfd(
        &self,
        target: &CartesianTarget,
        follow: bool,
        s: Smoothing,
    ) -> Result<(), RealmanError> {
        self.call(&rq::movep_canfd(target, follow, s)?)
            .await
            .map(drop)
    }

    /// `movej_follow`: online-planned joint follow (no reply).
    pub async fn movej_follow(&self, joints_rad: &[f64]) -> Result<(), RealmanError> {
        self.call(&rq::movej_follow(joints_rad)?).await.map(drop)
    }

    /// `movep_follow`: online-planned Cartesian follow (no reply).
    pub async fn movep_follow(&self, target: &CartesianTarget) -> Result<(), RealmanError> {
        self.call(&rq::movep_follow(target)?).await.map(drop)
    }

    // ---- stop / pause ----

    /// `set_arm_stop`: quick stop on the path.
    pub async fn stop(&self) -> Result<(), RealmanError> {
        self.set(rq::set_arm_stop()).await.map(drop)
    }

    /// `set_arm_slow_stop`: decelerate and stop on the path.
    pub async fn slow_stop(&self) -> Result<(), RealmanError> {
        self.set(rq::set_arm_slow_stop()).await.map(drop)
    }

    /// `set_arm_pause`.
    pub async fn pause(&self) -> Result<(), RealmanError> {
        self.set(rq::set_arm_pause()).await.map(drop)
    }

    /// `set_arm_continue`.
    pub async fn resume(&self) -> Result<(), RealmanError> {
        self.set(rq::set_arm_continue()).await.map(drop)
    }

    /// `set_delete_current_trajectory` (after a pause).
    pub async fn delete_current_trajectory(&self) -> Result<(), RealmanError> {
        self.set(rq::set_delete_current_trajectory())
            .await
            .map(drop)
    }

    /// `set_arm_delete_trajectory`: clear every queued trajectory (after a pause).
    pub async fn delete_all_trajectories(&self) -> Result<(), RealmanError> {
        self.set(rq::set_arm_delete_trajectory()).await.map(drop)
    }

    // ---- state ----

    /// `get_arm_current_trajectory`.
    pub async fn current_trajectory(&self) -> Result<CurrentTrajectory, RealmanError> {
        self.query(rq::get_arm_current_trajectory(), current_trajectory)
            .await
    }

    /// `get_current_arm_state` (either error form).
    pub async fn arm_state(&self) -> Result<ArmSnapshot, RealmanError> {
        self.query(rq::get_current_arm_state(), arm_snapshot).await
    }

    /// `get_joint_degree`, rad.
    pub async fn joint_positions(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_joint_degree(), |b| joints_rad(b, "joint"))
            .await
    }

    /// `get_arm_all_state`.
    pub async fn all_state(&self) -> Result<AllState, RealmanError> {
        self.query(rq::get_arm_all_state(), all_state).await
    }

    /// `get_joint_err_flag`: error bits and brakes.
    pub async fn joint_flags(&self) -> Result<JointFlags, RealmanError> {
        self.query(rq::get_joint_err_flag(), joint_flags).await
    }

    /// `get_controller_state`.
    pub async fn controller_state(&self) -> Result<ControllerState, RealmanError> {
        self.query(rq::get_controller_state(), controller_state)
            .await
    }

    /// `get_current_joint_temperature`, °C.
    pub async fn joint_temperatures(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_current_joint_temperature(), |b| {
            joint_measure(b, "joint_temperature")
        })
        .await
    }

    /// `get_current_joint_current`, A.
    pub async fn joint_currents(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_current_joint_current(), |b| {
            joint_measure(b, "joint_current")
        })
        .await
    }

    /// `get_current_joint_voltage`, V.
    pub async fn joint_voltages(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_current_joint_voltage(), |b| {
            joint_measure(b, "joint_voltage")
        })
        .await
    }

    /// `get_arm_power_state`.
    pub async fn power(&self) -> Result<bool, RealmanError> {
        self.query(rq::get_arm_power_state(), power_state).await
    }

    /// `set_arm_power`.
    pub async fn set_power(&self, on: bool) -> Result<(), RealmanError> {
        self.set(rq::set_arm_power(on)).await.map(drop)
    }

    /// `clear_system_err`.
    pub async fn clear_errors(&self) -> Result<(), RealmanError> {
        self.set(rq::clear_system_err()).await.map(drop)
    }

    /// `set_joint_clear_err` for one joint (1-based).
    pub async fn clear_joint_errors(&self, joint: u8) -> Result<(), RealmanError> {
        self.set(rq::set_joint_clear_err(joint)?).await.map(drop)
    }

    /// `save_device_info_all` (2nd-generation controllers).
    pub async fn save(&self) -> Result<(), RealmanError> {
        self.set(rq::save_device_info_all()).await.map(drop)
    }

    // ---- joint configuration ----

    /// `get_joint_min_pos`, rad.
    pub async fn joint_min_pos(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_joint_min_pos(), |b| joint_limits(b, "min_pos"))
            .await
    }

    /// `get_joint_max_pos`, rad.
    pub async fn joint_max_pos(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_joint_max_pos(), |b| joint_limits(b, "max_pos"))
            .await
    }

    /// `get_joint_max_speed`, rad/s.
    pub async fn joint_max_speed(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_joint_max_speed(), |b| joint_rates(b, "joint_speed"))
            .await
    }

    /// `get_joint_max_acc`, rad/s².
    pub async fn joint_max_acc(&self) -> Result<Vec<f64>, RealmanError> {
        self.query(rq::get_joint_max_acc(), |b| joint_rates(b, "joint_acc"))
            .await
    }

    /// `set_joint_min_pos` (joint disabled first).
    pub async fn set_joint_min_pos(&self, joint: u8, rad: f64) -> Result<(), RealmanError> {
        self.set(rq::set_joint_min_pos(joint, rad)?).await.map(drop)
    }

    /// `set_joint_max_pos` (joint disabled first).
    pub async fn set_joint_max_pos(&self, joint: u8, rad: f64) -> Result<(), RealmanError> {
        self.set(rq::set_joint_max_pos(joint, rad)?).await.map(drop)
    }

    /// `set_joint_max_speed`, rad/s.
    pub async fn set_joint_max_speed(&self, joint: u8, rad_s: f64) -> Result<(), RealmanError> {
        self.set(rq::set_joint_max_speed(joint, rad_s)?)
            .await
            .map(drop)
    }

    /// `set_joint_max_acc`, rad/s².
    pub async fn set_joint_max_acc(&self, joint: u8, rad_s2: f64) -> Result<(), RealmanError> {
        self.set(rq::set_joint_max_acc(joint, rad_s2)?)
            .await
            .map(drop)
    }

    /// `set_joint_en_state`.
    pub async fn set_joint_enabled(&self, joint: u8, enable: bool) -> Result<(), RealmanError> {
        self.set(rq::set_joint_en_state(joint, enable)?)
            .await
            .map(drop)
    }

    // ---- motion parameters ----

    /// `get_arm_max_line_speed`, m/s.
    pub async fn max_line_speed(&self) -> Result<f64, RealmanError> {
        self.query(rq::get_arm_max_line_speed(), |b| {
            milli_scalar(b, "arm_line_speed")
        })
        .await
    }

    /// `get_arm_max_line_acc`, m/s².
    pub async fn max_line_acc(&self) -> Result<f64, RealmanError> {
        self.query(rq::get_arm_max_line_acc(), |b| {
            milli_scalar(b, "arm_line_acc")
        })
        .await
    }

    /// `get_arm_max_angular_speed`, rad/s.
    pub async fn max_angular_speed(&self) -> Result<f64, RealmanError> {
        self.query(rq::get_arm_max_angular_speed(), |b| {
            milli_scalar(b, "arm_angular_speed")
        })
        .await
    }

    /// `get_arm_max_angular_acc`, rad/s².
    pub async fn max_angular_acc(&self) -> Result<f64, RealmanError> {
        self.query(rq::get_arm_max_angular_acc(), |b| {
            milli_scalar(b, "arm_angular_acc")
        })
        .await
    }

    /// `set_arm_max_line_speed`, m/s.
    pub async fn set_max_line_speed(&self, m_s: f64) -> Result<(), RealmanError> {
        self.set(rq::set_arm_max_line_speed(m_s)?).await.map(drop)
    }

    /// `set_arm_max_line_acc`, m/s².
    pub async fn set_max_line_acc(&self, m_s2: f64) -> Result<(), RealmanError> {
        self.set(rq::set_arm_max_line_acc(m_s2)?).await.map(drop)
    }

    /// `set_arm_max_angular_speed`, rad/s.
    pub async fn set_max_angular_speed(&self, rad_s: f64) -> Result<(), RealmanError> {
        self.set(rq::set_arm_max_angular_speed(rad_s)?)
            .await
            .map(drop)
    }

    /// `set_arm_max_angular_acc`, rad/s².
    pub async fn set_max_angular_acc(&self, rad_s2: f64) -> Result<(), RealmanError> {
        self.set(rq::set_arm_max_angular_acc(rad_s2)?)
            .await
            .map(drop)
    }

    /// `set_arm_init`: end-effector limits back to their defaults.
    pub async fn reset_motion_params(&self) -> Result<(), RealmanError> {
        self.set(rq::set_arm_init()).await.map(drop)
    }

    /// `get_collision_stage` (0..=8).
    pub async fn collision_stage(&self) -> Result<u8, RealmanError> {
        self.query(rq::get_collision_stage(), collision_stage).await
    }

    /// `set_collision_stage` (0..=8).
    pub async fn set_collision_stage(&self, stage: u8) -> Result<(), RealmanError> {
        self.set(rq::set_collision_stage(stage)?).await.map(drop)
    }

    /// `get_self_collision_enable`.
    pub async fn self_collision(&self) -> Result<bool, RealmanError> {
        self.query(rq::get_self_collision_enable(), self_collision)
            .await
    }

    /// `set_self_collision_enable`.
    pub async fn set_self_collision(&self, enable: bool) -> Result<(), RealmanError> {
        self.set(rq::set_self_collision_enable(enable))
            .await
            .map(drop)
    }

    /// `get_DH_data`.
    pub async fn dh_table(&self) -> Result<Vec<DhRow>, RealmanError> {
        self.query(rq::get_dh_data(), dh_table).await
    }

    /// `set_DH_data` (metrology use only).
    pub async fn set_dh_table(&self, rows: &[DhRow]) -> Result<(), RealmanError> {
        self.set(rq::set_dh_data(rows)?).await.map(drop)
    }

    /// `set_DH_data_default`.
    pub async fn reset_dh_table(&self) -> Result<(), RealmanError> {
        self.set(rq::set_dh_data_default()).await.map(drop)
    }

    /// `set_joint_zero_offset` (metrology use only).
    pub async fn set_joint_zero_offset(&self, offsets_rad: &[f64]) -> Result<(), RealmanError> {
        self.set(rq::set_joint_zero_offset(offsets_rad)?)
            .await
            .map(drop)
    }

    // ---- frames and mounting ----

    /// `get_current_tool_frame`.
    pub async fn tool_frame(&self) -> Result<ToolFrame, RealmanError> {
        self.query(rq::get_current_tool_frame(), tool_frame).await
    }

    /// `get_current_work_frame`.
    pub async fn work_frame(&self) -> Result<WorkFrame, RealmanError> {
        self.query(rq::get_current_work_frame(), work_frame).await
    }

    /// `get_install_pose`: rotation, pitch, azimuth in rad.
    pub async fn install_pose(&self) -> Result<[f64; 3], RealmanError> {
        self.query(rq::get_install_pose(), install_pose).await
    }

    /// `set_install_pose` (sent in whole degrees).
    pub async fn set_install_pose(
        &self,
        rot_pitch_azimuth_rad: [f64; 3],
    ) -> Result<(), RealmanError> {
        self.set(rq::set_install_pose(rot_pitch_azimuth_rad)?)
            .await
            .map(drop)
    }

    // ---- gripper and hand ----

    /// `get_gripper_state`.
    pub async fn gripper_state(&self) -> Result<GripperState, RealmanError> {
        self.query(rq::get_gripper_state(), gripper_state).await
    }

    /// `set_gripper_route` (0..=1000).
    pub async fn gripper_route(&self, min: u16, max: u16) -> Result<(), RealmanError> {
        self.set(rq::set_gripper_route(min, max)?).await.map(drop)
    }

    /// `set_gripper_position` (1..=1000); `block` waits for the gripper's arrival event.
    pub async fn gripper_position(&self, position: u16, block: bool) -> Result<(), RealmanError> {
        self.motion(
            rq::set_gripper_position(position, block)?,
            Device::Gripper,
            block,
        )
        .await
    }

    /// `set_gripper_pick`.
    pub async fn gripper_pick(
        &self,
        speed: u16,
        force: u16,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(
            rq::set_gripper_pick(speed, force, block)?,
            Device::Gripper,
            block,
        )
        .await
    }

    /// `set_gripper_pick_on` (continuous force grip).
    pub async fn gripper_pick_on(
        &self,
        speed: u16,
        force: u16,
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(
            rq::set_gripper_pick_on(speed, force, block)?,
            Device::Gripper,
            block,
        )
        .await
    }

    /// `set_gripper_release`.
    pub async fn gripper_release(&self, speed: u16, block: bool) -> Result<(), RealmanError> {
        self.motion(
            rq::set_gripper_release(speed, block)?,
            Device::Gripper,
            block,
        )
        .await
    }

    /// `set_hand_posture` (1..=40).
    pub async fn hand_posture(&self, posture: u8, block: bool) -> Result<(), RealmanError> {
        self.motion(rq::set_hand_posture(posture, block)?, Device::Hand, block)
            .await
    }

    /// `set_hand_seq` (1..=40).
    pub async fn hand_sequence(&self, seq: u8, block: bool) -> Result<(), RealmanError> {
        self.motion(rq::set_hand_seq(seq, block)?, Device::Hand, block)
            .await
    }

    /// `set_hand_angle`: six values 0..=1000, `None` keeps a finger where it is.
    pub async fn hand_angles(
        &self,
        angles: [Option<u16>; 6],
        block: bool,
    ) -> Result<(), RealmanError> {
        self.motion(rq::set_hand_angle(angles, block)?, Device::Hand, block)
            .await
    }

    /// `set_hand_speed` (1..=1000).
    pub async fn hand_speed(&self, speed: u16) -> Result<(), RealmanError> {
        self.set(rq::set_hand_speed(speed)?).await.map(drop)
    }

    /// `set_hand_force` (1..=1000).
    pub async fn hand_force(&self, force: u16) -> Result<(), RealmanError> {
        self.set(rq::set_hand_force(force)?).await.map(drop)
    }

    // ---- realtime push ----

    /// `get_realtime_push`.
    pub async fn realtime_push(&self) -> Result<PushConfig, RealmanError> {
        self.query(rq::get_realtime_push(), push_config).await
    }

    /// `set_realtime_push`.
    pub async fn set_realtime_push(&self, settings: &PushSettings) -> Result<(), RealmanError> {
        self.set(rq::set_realtime_push(settings)?).await.map(drop)
    }
}
