//! Host commands: what each frame does to the firmware state, and the replies it triggers.

use bus::CanFrame;
use nalgebra::{Isometry3, Vector3};

use super::{Firmware, LeaderHoming, Motion, TargetKey};
use crate::piper::codec::arm::{self, mdeg_to_rad, FirmwareInfo};
use crate::piper::codec::host::{
    self, CtrlMode, HostCommand, LinkageRole as WireRole, MotorSelect, MoveCPoint, MoveMode,
    PosePart, QuickStop,
};
use crate::piper::codec::DecodeError;
use crate::piper::flash::{
    rules as flash_rules, LinkageRole, DEFAULT_END_VEL_ACC, MAX_ACC_CEILING_CRAD_S2,
    MAX_SPEED_CEILING_CRAD_S,
};
use crate::piper::ids;
use crate::piper::kin;
use crate::piper::pose::WirePose;
use crate::piper::trajectory::{JointMove, PathMove};

/// Identity strings of the 0x4AF reply other than the software version.
const HARDWARE_VERSION: &str = "H-V1.2-1";
const MOTOR_RATIO: &str = "10";
const NODE_TYPE: &str = "ARM_MC";
const PRODUCTION_DATE: &str = "250925";
const NODE_NUMBER: &str = "15";

/// Minimum delay of the 0x4AF reply, ms. piper_sdk clears its firmware buffer *after* sending
/// the query, so an instant reply could be wiped; its README waits ~25 ms for the answer.
const FIRMWARE_REPLY_DELAY_MS: u64 = 5;

/// Spacing of Cartesian path samples, m and rad.
const PATH_STEP_M: f64 = 0.002;
const PATH_STEP_RAD: f64 = 0.02;
const PATH_MAX_SAMPLES: usize = 600;

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
            } => {
                let (at, bit) = match part {
                    PosePart::XY => (0, 1),
                    PosePart::ZRx => (2, 2),
                    PosePart::RyRz => (4, 4),
                };
                self.pose_cmd[at] = first;
                self.pose_cmd[at + 1] = second;
                self.pose_parts |= bit;
                self.pose_dirty = true;
            }
            HostCommand::Joint {
                pair,
                first_mdeg,
                second_mdeg,
            } => {
                self.joint_cmd_mdeg[2 * pair] = first_mdeg;
                self.joint_cmd_mdeg[2 * pair + 1] = second_mdeg;
                self.joint_cmd_dirty = true;
            }
            HostCommand::MoveCPoint(p) => {
                if self.pose_parts == 0b111 {
                    let idx = match p {
                        MoveCPoint::Start => 0,
                        MoveCPoint::Middle => 1,
                        MoveCPoint::End => 2,
                    };
                    self.move_c_points[idx] = Some(self.pose_cmd);
                    // The pose frames before a 0x158 are an arc point, not a MOVE P/L target.
                    self.pose_dirty = false;
                    if p == MoveCPoint::End && self.move_mode == MoveMode::C {
                        self.plan_arc();
                    }
                }
            }
            HostCommand::Gripper(g) => self.on_gripper(g),
            HostCommand::Mit { joint, cmd } => {
                if self.accepts_motion() && self.mit_active() {
                    self.mit_cmd[joint] = Some(cmd);
                }
            }
            HostCommand::Cpv {
                motor,
                mode,
                param,
                value,
            } => {
                let key = (motor, param);
                let reply_value = match mode {
                    b'w' => {
                        self.cpv_params.insert(key, value);
                        value
                    }
                    b'r' => self.cpv_params.get(&key).copied().unwrap_or(0),
                    _ => return,
                };
                self.out
                    .push(arm::encode_cpv_reply(motor, param, reply_value));
            }
            HostCommand::LeaderHome { bytes } => self.on_leader_home(bytes),
            HostCommand::UpgradeMode(m) => self.silent = m != 0,
            HostCommand::Linkage(cfg) => {
                match cfg.role {
                    WireRole::Leader => self.flash.linkage_role = LinkageRole::Leader,
                    WireRole::Follower => {
                        self.flash.linkage_role = LinkageRole::Follower;
                        if self.leader_active {
                            self.leader_active = false;
                            self.ctrl_mode = CtrlMode::Standby;
                            self.hold_here();
                        }
                    }
                    WireRole::NoOp => {}
                }
                self.flash.feedback_offset = cfg.feedback_offset;
                self.flash.control_offset = cfg.control_offset;
                self.flash.target_offset = cfg.target_offset;
                self.mark_flash_dirty();
            }
            HostCommand::MotorEnable { motor, enable } => self.on_motor_enable(motor, enable),
            HostCommand::JointQuery {
                joint,
                acceleration,
            } => {
                let f = if acceleration {
                    arm::encode_joint_acc(joint, self.flash.max_acc_crad_s2[joint])
                } else {
                    arm::encode_joint_limits(
                        joint,
                        self.flash.max_angle_ddeg[joint],
                        self.flash.min_angle_ddeg[joint],
                        self.flash.max_speed_crad_s[joint],
                    )
                };
                self.out.push(f);
            }
            HostCommand::SetJointLimits {
                joint,
                max_angle_ddeg,
                min_angle_ddeg,
                max_speed_crad_s,
            } => {
                let max = max_angle_ddeg.unwrap_or(self.flash.max_angle_ddeg[joint]);
                let min = min_angle_ddeg.unwrap_or(self.flash.min_angle_ddeg[joint]);
                if let Err(problem) = flash_rules::joint_limits(min, max) {
                    tracing::debug!(joint = joint + 1, %problem, "0x474 ignored");
                    return;
                }
                self.flash.max_angle_ddeg[joint] = max;
                self.flash.min_angle_ddeg[joint] = min;
                if let Some(s) = max_speed_crad_s {
                    self.flash.max_speed_crad_s[joint] = s.min(MAX_SPEED_CEILING_CRAD_S);
                }
                self.mark_flash_dirty();
                self.out.push(arm::encode_ack(0x74, false, 0));
            }
            HostCommand::JointConfig {
                joint,
                set_zero,
                max_acc_crad_s2,
                clear_error,
            } => {
                let joints: Vec<usize> = match joint {
                    Some(j) => vec![j],
                    None => (0..6).collect(),
                };
                let mut zero_ok = false;
                if set_zero {
                    // The SDK's zeroing flow disables the motor first; an energised joint
                    // refuses (ack byte 1 = 0).
                    if joints.iter().all(|&j| !self.enabled[j]) {
                        for &j in &joints {
                            self.flash.zero_offset_rad[j] = self.q_phys(j);
                            self.hold_ref[j] = self.q_phys(j);
                        }
                        zero_ok = true;
                    }
                }
                if let Some(acc) = max_acc_crad_s2 {
                    for &j in &joints {
                        self.flash.max_acc_crad_s2[j] = acc.min(MAX_ACC_CEILING_CRAD_S2);
                    }
                }
                if clear_error {
                    for &j in &joints {
                        self.faults.clear_latched(j);
                    }
                }
                self.mark_flash_dirty();
                self.out.push(arm::encode_ack(0x75, zero_ok, 0));
            }
            HostCommand::ParamQuery(p) => {
                match p.query {
                    1 => self.out.push(arm::encode_four_u16(
                        ids::END_VEL_ACC_REPLY,
                        self.flash.end_vel_acc,
                    )),
                    2 => self.out.push(arm::encode_six_u8(
                        ids::COLLISION_REPLY,
                        self.flash.collision_levels,
                    )),
                    3 => self.out.push(arm::encode_trajectory_index(
                        self.trajectory_name_index,
                        self.trajectory_crc,
                    )),
                    4 => self.out.push(arm::encode_gripper_teach(
                        self.flash.pendant_travel_pct,
                        self.flash.gripper_max_stroke_mm,
                        self.flash.pendant_friction,
                    )),
                    _ => {}
                }
                match p.reset {
                    1 => self.flash.end_vel_acc = DEFAULT_END_VEL_ACC,
                    2 => self.flash.reset_joint_params(),
                    _ => {}
                }
                if p.periodic_48x != 0 {
                    self.periodic_48x = p.periodic_48x == self.config.periodic_48x_on_code;
                }
                if let Some(payload) = p.payload {
                    self.flash.payload = payload;
                }
                let is_set = p.reset != 0 || p.periodic_48x != 0 || p.payload.is_some();
                if is_set {
                    self.mark_flash_dirty();
                    self.out.push(arm::encode_ack(0x77, false, 0));
                }
            }
            HostCommand::SetEndVelAcc(e) => {
                let fields = [
                    e.linear_vel_mm_s,
                    e.angular_vel_mrad_s,
                    e.linear_acc_mm_s2,
                    e.angular_acc_mrad_s2,
                ];
                for (slot, v) in self.flash.end_vel_acc.iter_mut().zip(fields) {
                    if let Some(v) = v {
                        *slot = v;
                    }
                }
                self.mark_flash_dirty();
                self.out.push(arm::encode_ack(0x79, false, 0));
            }
            HostCommand::SetCollision(levels) => {
                for (slot, l) in self.flash.collision_levels.iter_mut().zip(levels) {
                    if let Some(l) = l {
                        *slot = l;
                    }
                }
                self.mark_flash_dirty();
                self.out.push(arm::encode_ack(0x7A, false, 0));
            }
            HostCommand::SetGripperTeach {
                travel_pct,
                max_stroke_mm,
                friction,
            } => {
                // Out-of-range fields are left unchanged (the SDK validates the same ranges).
                if flash_rules::PENDANT_TRAVEL_PCT.contains(&travel_pct) {
                    self.flash.pendant_travel_pct = travel_pct;
                }
                if flash_rules::GRIPPER_MAX_STROKE_MM.contains(&max_stroke_mm) {
                    self.flash.gripper_max_stroke_mm = max_stroke_mm;
                }
                if flash_rules::PENDANT_FRICTION.contains(&friction) {
                    self.flash.pendant_friction = friction;
                }
                self.mark_flash_dirty();
            }
            HostCommand::FirmwareQuery => {
                let frames = arm::encode_firmware(&FirmwareInfo {
                    hardware: HARDWARE_VERSION,
                    motor_ratio: MOTOR_RATIO,
                    node_type: NODE_TYPE,
                    software: self.profile.version_string(),
                    production_date: PRODUCTION_DATE,
                    node_number: NODE_NUMBER,
                });
                // Frames are handled before the wake-up's batch of ticks runs, so the delay is
                // counted from the end of that batch: otherwise, with several ticks per wake-up,
                // the reply would leave in the same wake-up as the query arrived, i.e. at once
                // in real time, and race the SDK's buffer reset.
                let batch = u64::from(self.config.ticks_per_wake.clamp(1, 25));
                let due = self.ticks + batch + FIRMWARE_REPLY_DELAY_MS;
                self.delayed.extend(frames.into_iter().map(|f| (due, f)));
            }
        }
    }

    fn on_motion_ctrl_1(&mut self, m: host::MotionCtrl1) {
        match m.quick_stop {
            QuickStop::Stop => {
                self.estop = true;
                self.abort_motion();
            }
            QuickStop::Reset => self.reset(),
            QuickStop::None => {}
        }
        match m.trajectory {
            0x07 => self.out.push(arm::encode_ack(0x50, false, m.point_index)),
            0x08 => {
                self.trajectory_name_index = m.name_index;
                self.trajectory_crc = m.crc16;
                let mut d = [0u8; 8];
                d[0] = 0x50;
                d[2] = m.point_index;
                d[3] = host::CONFIRM;
                d[4..6].copy_from_slice(&m.name_index.to_be_bytes());
                d[6..8].copy_from_slice(&m.crc16.to_be_bytes());
                self.out.push(crate::piper::codec::frame(ids::SET_ACK, &d));
            }
            _ => {}
        }
        if m.drag_teach != 0 {
            self.teach_status = m.drag_teach;
        }
    }

    /// 0x150 = 0x02: motors off, errors and flags cleared, back to standby.
    fn reset(&mut self) {
        self.estop = false;
        self.enabled = [false; 6];
        self.gripper.enabled = false;
        self.move_mode = MoveMode::P;
        self.mit_flag = false;
        self.mit_sticky = false;
        self.speed_pct = 0;
        self.teach_status = 0;
        self.command_status = None;
        self.target_limit_bits = 0;
        for j in 0..6 {
            self.faults.clear_latched(j);
        }
        self.hold_here();
        self.enter_standby();
    }

    fn enter_standby(&mut self) {
        if self.flash.linkage_role == LinkageRole::Leader {
            self.leader_active = true;
            self.leader_homing = LeaderHoming::Drag;
            self.ctrl_mode = CtrlMode::LinkageTeach;
        } else if self.ctrl_mode != CtrlMode::Teach {
            self.ctrl_mode = CtrlMode::Standby;
        }
    }

    fn on_mode_ctrl(&mut self, m: host::ModeCtrl) {
        if self.estop || self.ctrl_mode == CtrlMode::Teach {
            return;
        }
        match m.ctrl_mode {
            // Drag teach is entered by the button only (spec §8.3).
            CtrlMode::Teach | CtrlMode::LinkageTeach => return,
            CtrlMode::Standby => {
                self.hold_here();
                self.enter_standby();
                return;
            }
            mode => self.ctrl_mode = mode,
        }
        let was_mit = self.mit_active();
        if let Some(mm) = m.move_mode {
            // Up to S-V1.8-5 the arm cannot leave MIT for position-velocity without a reset
            // (spec §5.1, (piper_sdk#83)).
            if !(self.mit_sticky && mm != MoveMode::Mit) {
                self.move_mode = mm;
            }
        }
        if let Some(mit) = m.mit {
            if !self.mit_sticky || mit {
                self.mit_flag = mit;
            }
        }
        if self.mit_active() {
            if !was_mit {
                self.hold_here();
            }
            if self.profile < crate::piper::profile::FirmwareProfile::V1_8_8 {
                self.mit_sticky = true;
            }
        }
        self.speed_pct = m.speed_pct;
        if flash_rules::INSTALL_POSITIONS.contains(&m.install_position)
            && self.flash.install_position != m.install_position
        {
            self.flash.install_position = m.install_position;
            self.mark_flash_dirty();
        }
        if self.move_mode == MoveMode::C && self.move_c_points.iter().all(Option::is_some) {
            self.plan_arc();
        }
    }

    fn on_gripper(&mut self, g: host::GripperCtrl) {
        let max_stroke_mm = self.flash.gripper_max_stroke_mm;
        // A gripper whose travel range was never set ignores commands (spec §4.4).
        if max_stroke_mm == 0 {
            return;
        }
        if g.set_zero && !g.enable {
            self.flash.gripper_zero_offset_m = self.gripper_stroke_phys_m();
            self.flash.gripper_homed = true;
            self.mark_flash_dirty();
        }
        let powered = !self.faults.gripper_sensor_fault && !self.estop;
        self.gripper.enabled = g.enable && powered;
        if g.enable {
            let max_m = f64::from(max_stroke_mm) * 1e-3;
            let stroke = (f64::from(g.stroke_um) * 1e-6).clamp(0.0, max_m);
            self.gripper.target_stroke_m = stroke + self.flash.gripper_zero_offset_m;
            self.gripper.effort_nm = (f64::from(g.effort_mnm) / 1000.0).clamp(0.0, 5.0);
        }
    }

    fn on_leader_home(&mut self, bytes: [u8; 3]) {
        if !self.leader_active || bytes[0] != 1 {
            return;
        }
        match (bytes[1], bytes[2]) {
            (0, 0) => {
                self.leader_homing = LeaderHoming::Drag;
                self.hold_here();
            }
            (with, 1) => {
                self.leader_homing = LeaderHoming::Homing {
                    with_follower: with == 0,
                };
                let target: [f64; 6] = std::array::from_fn(|j| self.flash.zero_offset_rad[j]);
                let (q, v) = (self.physical_joints(), [0.0; 6]);
                let (vl, al) = self.motion_limits_at(30);
                self.start_motion(Motion::Joint(JointMove::new(q, v, target, vl, al)));
            }
            _ => {}
        }
    }

    fn on_motor_enable(&mut self, motor: MotorSelect, enable: bool) {
        if enable && self.estop {
            return;
        }
        let joints: Vec<usize> = match motor {
            MotorSelect::Joint(j) => vec![j],
            MotorSelect::AllWithGripper | MotorSelect::All => (0..6).collect(),
        };
        for j in joints {
            if enable {
                if !self.enabled[j] && !self.faults.joint_unpowered(j) {
                    self.enabled[j] = true;
                    // The loop first has to catch a joint that may still be moving (a
                    // wrist falling since it was disabled): not a collision.
                    self.collision_residual[j] = 0.0;
                    self.collision_blank_ticks[j] = super::faults::ENABLE_COLLISION_BLANK_MS;
                    if self.motion.is_none() {
                        self.hold_ref[j] = self.q_phys(j);
                        self.ref_vel[j] = 0.0;
                    }
                }
            } else {
                self.enabled[j] = false;
            }
        }
        if !enable && self.motion.is_some() {
            self.hold_here();
        }
        if matches!(motor, MotorSelect::AllWithGripper | MotorSelect::All)
            && self.flash.gripper_max_stroke_mm != 0
        {
            self.gripper.enabled = enable && !self.faults.gripper_sensor_fault;
        }
    }

    fn motion_limits_at(&self, pct: u8) -> ([f64; 6], [f64; 6]) {
        let p = f64::from(pct) / 100.0;
        (
            std::array::from_fn(|j| self.flash.max_speed_rad_s(j) * p),
            std::array::from_fn(|j| self.flash.max_acc_rad_s2(j)),
        )
    }

    /// Turn the latest joint / pose targets into a motion (called once per tick, so a
    /// 0x155–0x157 triple that arrives within one millisecond plans once).
    pub(crate) fn apply_pending_targets(&mut self) {
        for j in 0..6 {
            if !self.enabled[j] && self.motion.is_none() {
                self.hold_ref[j] = self.q_phys(j);
                self.ref_vel[j] = 0.0;
            }
        }
        if self.joint_cmd_dirty {
            self.joint_cmd_dirty = false;
            let joint_mode = matches!(self.move_mode, MoveMode::J | MoveMode::Cpv);
            if self.accepts_motion() && joint_mode {
                let target: [f64; 6] = std::array::from_fn(|j| mdeg_to_rad(self.joint_cmd_mdeg[j]));
                self.go_to_joints(target, self.mit_flag);
            }
        }
        if self.pose_dirty && self.pose_parts == 0b111 {
            self.pose_dirty = false;
            let key = TargetKey::Pose(self.move_mode, self.pose_cmd);
            // A repeated pose keeps the running profile: re-solving the IK from where the arm
            // is now would give a slightly different target, and a MOVE L would restart its
            // path from rest (a streaming client then crawls).
            let repeated = self.target_key == Some(key);
            let pose_mode = matches!(self.move_mode, MoveMode::P | MoveMode::L);
            if self.accepts_motion() && pose_mode && !repeated {
                let target = WirePose::from_wire(self.pose_cmd).to_isometry();
                let planned = if self.move_mode == MoveMode::P {
                    let seed = self.reported_joints();
                    match kin::solve(&target, &seed, &self.limits(), self.profile, false) {
                        Some(q) => self.go_to_joints(q, false),
                        None => {
                            self.reject(0x02, 0);
                            false
                        }
                    }
                } else {
                    let start = self.reference_pose();
                    let poses = line_samples(&start, &target);
                    self.follow_poses(&poses, &start, &target)
                };
                if planned {
                    self.target_key = Some(key);
                }
            }
        }
    }

    /// Reject a command with a status code (0x02 no solution, 0x04 limit) and limit bits.
    fn reject(&mut self, code: u8, limit_bits: u8) {
        tracing::debug!(code, limit_bits, "Piper command rejected");
        self.command_status = Some(code);
        self.target_limit_bits = limit_bits;
    }

    /// Plan a joint move to `target_reported`; false when it was rejected.
    fn go_to_joints(&mut self, target_reported: [f64; 6], direct: bool) -> bool {
        let mut bits = 0u8;
        for (j, &t) in target_reported.iter().enumerate() {
            let (lo, hi) = self.flash.limits_rad(j);
            if t < lo - 1e-9 || t > hi + 1e-9 {
                bits |= 1 << j;
            }
        }
        if bits != 0 {
            self.reject(0x04, bits);
            return false;
        }
        self.command_status = None;
        self.target_limit_bits = 0;
        let target: [f64; 6] =
            std::array::from_fn(|j| target_reported[j] + self.flash.zero_offset_rad[j]);
        if direct {
            // "High-follow" (MOVE J + 0xAD): no smoothing, the target goes straight to the
            // position loop.
            self.motion = None;
            self.target_key = None;
            self.hold_ref = target;
            self.ref_vel = [0.0; 6];
            self.settling = true;
            return true;
        }
        if let Some(m) = &self.motion {
            if m.target() == target {
                return true;
            }
        } else if self.hold_ref == target {
            return true;
        }
        // The new profile starts from the reference position *and velocity*, so a changed
        // target blends from the current speed.
        let (q, v) = self.reference_state();
        let (vl, al) = self.motion_limits();
        self.start_motion(Motion::Joint(JointMove::new(q, v, target, vl, al)));
        true
    }

    /// Flange pose of the current reference (where the arm is heading now).
    fn reference_pose(&self) -> Isometry3<f64> {
        let q: [f64; 6] = std::array::from_fn(|j| self.hold_ref[j] - self.flash.zero_offset_rad[j]);
        kin::flange(&q, self.profile)
    }

    /// IK every sample, then follow the joint-space path timed by the end-effector limits.
    /// False when the path was rejected.
    fn follow_poses(
        &mut self,
        poses: &[Isometry3<f64>],
        start: &Isometry3<f64>,
        end: &Isometry3<f64>,
    ) -> bool {
        let limits = self.limits();
        let mut seed: [f64; 6] =
            std::array::from_fn(|j| self.hold_ref[j] - self.flash.zero_offset_rad[j]);
        let mut waypoints = Vec::with_capacity(poses.len());
        for p in poses {
            match kin::solve(p, &seed, &limits, self.profile, true) {
                Some(q) => {
                    // A jump between neighbouring samples means the IK switched branch: the
                    // straight path crosses a singularity.
                    if (0..6).any(|j| (q[j] - seed[j]).abs() > 0.5) && !waypoints.is_empty() {
                        self.reject(0x03, 0);
                        return false;
                    }
                    seed = q;
                    waypoints.push(std::array::from_fn(|j| {
                        q[j] + self.flash.zero_offset_rad[j]
                    }));
                }
                None => {
                    self.reject(0x02, 0);
                    return false;
                }
            }
        }
        if let Some(Motion::Path(p)) = &self.motion {
            if waypoints.last() == Some(&p.target()) {
                return true;
            }
        }
        self.command_status = None;
        self.target_limit_bits = 0;
        let length = path_length(poses);
        let angle = start.rotation.angle_to(&end.rotation).max(1e-9);
        let pct = f64::from(self.speed_pct.clamp(1, 100)) / 100.0;
        let [v_lin, v_ang, a_lin, a_ang] = self.flash.end_vel_acc.map(|x| f64::from(x) / 1000.0);
        let s_dot = (v_lin * pct / length.max(1e-9)).min(v_ang * pct / angle);
        let s_ddot = (a_lin / length.max(1e-9)).min(a_ang / angle);
        let (vl, al) = self.motion_limits();
        // Blend from the current reference velocity (a changed target mid-move).
        let (_, v_ref) = self.reference_state();
        self.start_motion(Motion::Path(
            PathMove::new(waypoints, s_dot, s_ddot, vl, al).with_initial_velocity(v_ref),
        ));
        true
    }

    /// MOVE C: a line to the start point if the arm is elsewhere, then the arc through the
    /// three points; orientation interpolated from start to end.
    fn plan_arc(&mut self) {
        let [Some(a), Some(b), Some(c)] = self.move_c_points else {
            return;
        };
        self.move_c_points = [None; 3];
        let key = TargetKey::Arc([a, b, c]);
        if !self.accepts_motion() || self.target_key == Some(key) {
            return;
        }
        let (pa, pb, pc) = (
            WirePose::from_wire(a).to_isometry(),
            WirePose::from_wire(b).to_isometry(),
            WirePose::from_wire(c).to_isometry(),
        );
        let Some(arc) = arc_samples(&pa, &pb, &pc) else {
            self.reject(0x02, 0);
            return;
        };
        let start = self.reference_pose();
        let mut poses = Vec::new();
        if (start.translation.vector - pa.translation.vector).norm() > 0.001 {
            poses.extend(line_samples(&start, &pa));
        }
        poses.extend(arc);
        if self.follow_poses(&poses, &start, &pc) {
            self.target_key = Some(key);
        }
    }
}

fn path_length(poses: &[Isometry3<f64>]) -> f64 {
    poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum()
}

/// Evenly spaced poses on the straight line from `a` to `b` (slerped orientation).
fn line_samples(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vec<Isometry3<f64>> {
    let dist = (b.translation.vector - a.translation.vector).norm();
    let angle = a.rotation.angle_to(&b.rotation);
    let n = ((dist / PATH_STEP_M).max(angle / PATH_STEP_RAD).ceil() as usize)
        .clamp(1, PATH_MAX_SAMPLES);
    (0..=n)
        .map(|i| a.lerp_slerp(b, i as f64 / n as f64))
        .collect()
}

/// Poses on the circle through three points, from `a` via `b` to `c`; `None` when the points
/// are (nearly) collinear.
fn arc_samples(
    a: &Isometry3<f64>,
    b: &Isometry3<f64>,
    c: &Isometry3<f64>,
) -> Option<Vec<Isometry3<f64>>> {
    let (p1, p2, p3) = (
        a.translation.vector,
        b.translation.vector,
        c.translation.vector,
    );
    let (u, w) = (p2 - p1, p3 - p1);
    let n = u.cross(&w);
    let n2 = n.norm_squared();
    if n2 < 1e-12 {
        return None;
    }
    // Circumcentre of the triangle.
    let center =
        p1 + (w.norm_squared() * n.cross(&u) + u.norm_squared() * w.cross(&n)) / (2.0 * n2);
    let r1 = p1 - center;
    let radius = r1.norm();
    let axis = n.normalize();
    let angle_of = |p: Vector3<f64>| {
        let r = p - center;
        let x = r1.normalize();
        let y = axis.cross(&x);
        let ang = r.dot(&y).atan2(r.dot(&x));
        if ang < 0.0 {
            ang + 2.0 * std::f64::consts::PI
        } else {
            ang
        }
    };
    // Going around `axis` from p1, p2 comes before p3 by construction of the normal.
    let total = angle_of(p3);
    let count = ((radius * total / PATH_STEP_M).ceil() as usize).clamp(2, PATH_MAX_SAMPLES);
    let x = r1.normalize();
    let y = axis.cross(&x);
    Some(
        (0..=count)
            .map(|i| {
                let f = i as f64 / count as f64;
                let th = total * f;
                let p = center + radius * (th.cos() * x + th.sin() * y);
                let rot = a.rotation.slerp(&c.rotation, f);
                Isometry3::from_parts(p.into(), rot)
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_passes_through_the_middle_point() {
        let a = Isometry3::translation(0.3, 0.0, 0.2);
        let b = Isometry3::translation(0.2, 0.1, 0.2);
        let c = Isometry3::translation(0.1, 0.0, 0.2);
        let arc = arc_samples(&a, &b, &c).unwrap();
        let near_b = arc
            .iter()
            .map(|p| (p.translation.vector - b.translation.vector).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(near_b < 0.002, "{near_b}");
        assert!((arc.last().unwrap().translation.vector - c.translation.vector).norm() < 1e-9);
        assert!(arc_samples(&a, &Isometry3::translation(0.2, 0.0, 0.2), &c).is_none());
    }

    /// Ticks until the first 0x4AF reply frame leaves after a query, for a given batching.
    fn firmware_reply_ticks(ticks_per_wake: u32) -> (u64, usize) {
        let mut fw = Firmware::new(crate::piper::PiperConfig {
            ticks_per_wake,
            ..crate::piper::PiperConfig::default()
        })
        .unwrap();
        let mut out = Vec::new();
        fw.tick();
        fw.drain_output_into(&mut out);
        let query = CanFrame::standard(ids::FIRMWARE, &[1, 0, 0, 0, 0, 0, 0, 0]).unwrap();
        fw.handle_frame(&query);
        for tick in 1..=100u64 {
            fw.tick();
            out.clear();
            fw.drain_output_into(&mut out);
            let replies = out.iter().filter(|f| f.raw_id() == 0x4AF).count();
            if replies > 0 {
                return (tick, replies);
            }
        }
        panic!("no 0x4AF reply within 100 ticks");
    }

    #[test]
    fn firmware_reply_leaves_a_wake_up_after_the_query_at_the_earliest() {
        // One tick per wake-up: the reply needs FIRMWARE_REPLY_DELAY_MS ticks after the batch
        // of the wake-up that handled the query.
        assert_eq!(firmware_reply_ticks(1), (1 + FIRMWARE_REPLY_DELAY_MS, 11));
        // Five ticks per wake-up (armhil sim piper): the five ticks after the query run at
        // once, in the same wake-up, so the reply must wait past them to be late in real time.
        let (ticks, frames) = firmware_reply_ticks(5);
        assert_eq!(frames, 11);
        assert!(ticks >= 5 + FIRMWARE_REPLY_DELAY_MS, "{ticks}");
    }
}
