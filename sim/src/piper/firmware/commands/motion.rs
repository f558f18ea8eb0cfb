//! Motion commands: modes, targets (joint, pose, MOVE C points, MIT), enabling, stopping, and
//! the planning that turns a target into a joint or Cartesian motion.

use nalgebra::Isometry3;

use super::path::{arc_samples, line_samples, path_length};
use crate::piper::codec::arm::{self, mdeg_to_rad};
use crate::piper::codec::host::{
    self, CtrlMode, MotorSelect, MoveCPoint, MoveMode, PosePart, QuickStop,
};
use crate::piper::codec::mit::MitCommand;
use crate::piper::firmware::{Firmware, LeaderHoming, Motion, TargetKey};
use crate::piper::flash::{rules as flash_rules, LinkageRole};
use crate::piper::ids;
use crate::piper::kin;
use crate::piper::pose::WirePose;
use crate::piper::trajectory::{JointMove, PathMove};

impl Firmware {
    /// 0x152–0x154: one pair of the end-pose target; the third part completes it.
    pub(super) fn on_end_pose(&mut self, part: PosePart, first: i32, second: i32) {
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

    /// 0x155–0x157: one pair of the joint target.
    pub(super) fn on_joint_pair(&mut self, pair: usize, first_mdeg: i32, second_mdeg: i32) {
        self.joint_cmd_mdeg[2 * pair] = first_mdeg;
        self.joint_cmd_mdeg[2 * pair + 1] = second_mdeg;
        self.joint_cmd_dirty = true;
    }

    /// 0x158: the last end pose is a MOVE C point; the end point plans the arc.
    pub(super) fn on_move_c_point(&mut self, p: MoveCPoint) {
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

    /// 0x15A–0x15F: one joint's MIT command, taken in MIT mode only.
    pub(super) fn on_mit(&mut self, joint: usize, cmd: MitCommand) {
        if self.accepts_motion() && self.mit_active() {
            self.mit_cmd[joint] = Some(cmd);
        }
    }

    pub(super) fn on_motion_ctrl_1(&mut self, m: host::MotionCtrl1) {
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

    pub(super) fn on_mode_ctrl(&mut self, m: host::ModeCtrl) {
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

    pub(super) fn on_gripper(&mut self, g: host::GripperCtrl) {
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

    pub(super) fn on_leader_home(&mut self, bytes: [u8; 3]) {
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

    pub(super) fn on_motor_enable(&mut self, motor: MotorSelect, enable: bool) {
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
                    self.collision_blank_ticks[j] =
                        crate::piper::firmware::protections::ENABLE_COLLISION_BLANK_MS;
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
