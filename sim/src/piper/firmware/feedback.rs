//! Periodic frames: 200 Hz arm and high-speed driver groups, 40 Hz low-speed driver group,
//! optional 0x481–0x486, and what a leader arm emits instead.

use super::{Firmware, LeaderHoming, LOW_RATE_DIVIDER, STEP_S};
use crate::piper::codec::arm::{self, rad_to_mdeg, sat_i16, sat_i32, sat_u16, ArmStatusFrame};
use crate::piper::codec::host::{self as hostc, CtrlMode, GripperCtrl, ModeCtrl, MoveMode};
use crate::piper::faults::{driver_bits, gripper_bits};
use crate::piper::ids;
use crate::piper::kin;
use crate::piper::pose::WirePose;

impl Firmware {
    /// 0x26x byte 5 bit 6.
    pub(crate) fn joint_enabled_bit(&self, j: usize) -> bool {
        self.enabled[j] && !self.faults.joint_unpowered(j)
    }

    /// 0x26x byte 5.
    pub(crate) fn driver_status_bits(&self, j: usize) -> u8 {
        let mut b = self.faults.driver_bits(j);
        if self.joint_enabled_bit(j) {
            b |= driver_bits::ENABLED;
        }
        b
    }

    fn status_frame(&self) -> ArmStatusFrame {
        ArmStatusFrame {
            ctrl_mode: self.ctrl_mode as u8,
            arm_status: self.arm_status_code(),
            mode_feed: self.move_mode.code(self.profile),
            teach_status: self.teach_status,
            motion_status: self.motion_status(),
            trajectory_num: self.trajectory_num,
            limit_bits: self.limit_bits(),
            comm_bits: self.faults.comm_bits(),
        }
    }

    /// Reported gripper stroke, µm (0 when the stroke range was never set).
    fn gripper_stroke_um(&self) -> i32 {
        if self.flash.gripper_max_stroke_mm == 0 {
            return 0;
        }
        sat_i32(((self.gripper_stroke_phys_m() - self.flash.gripper_zero_offset_m) * 1e6).round())
    }

    fn gripper_status(&self) -> u8 {
        let mut b = 0;
        if self.faults.voltage_v() < super::protections::UNDER_VOLTAGE_V {
            b |= gripper_bits::UNDER_VOLTAGE;
        }
        if self.faults.gripper_sensor_fault {
            b |= gripper_bits::SENSOR_FAULT;
        }
        if self.gripper.enabled {
            b |= gripper_bits::ENABLED;
        }
        if self.flash.gripper_homed {
            b |= gripper_bits::HOMED;
        }
        b
    }

    /// 0x2A1–0x2A8 then 0x251–0x256, back to back.
    pub(crate) fn emit_high_rate(&mut self) {
        let fb = u16::from(self.flash.feedback_offset);
        let status = self.status_frame();
        self.out.push(status.encode(ids::ARM_STATUS + fb));
        let pose = WirePose::from_isometry(&self.flange_pose()).to_wire();
        self.out
            .push(arm::encode_pair(ids::FB_END_POSE_XY + fb, pose[0], pose[1]));
        self.out.push(arm::encode_pair(
            ids::FB_END_POSE_ZRX + fb,
            pose[2],
            pose[3],
        ));
        self.out.push(arm::encode_pair(
            ids::FB_END_POSE_RYRZ + fb,
            pose[4],
            pose[5],
        ));
        let q: [i32; 6] = std::array::from_fn(|j| rad_to_mdeg(self.q_reported(j)));
        self.out
            .push(arm::encode_pair(ids::FB_JOINT_12 + fb, q[0], q[1]));
        self.out
            .push(arm::encode_pair(ids::FB_JOINT_34 + fb, q[2], q[3]));
        self.out
            .push(arm::encode_pair(ids::FB_JOINT_56 + fb, q[4], q[5]));
        let torque_mnm =
            sat_i16((self.gripper.force_n / super::GRIPPER_FORCE_N_PER_NM * 1000.0).round());
        let gripper = arm::encode_gripper(
            ids::FB_GRIPPER + fb,
            self.gripper_stroke_um(),
            torque_mnm,
            self.gripper_status(),
        );
        self.out.push(gripper);
        for j in 0..6 {
            if self.faults.comm_lost(j) {
                continue;
            }
            let f = arm::encode_high_speed(
                j,
                sat_i16((self.v_phys(j) * 1000.0).round()),
                sat_i16((self.motors[j].current_a() * 1000.0).round()),
                sat_i32((self.q_reported(j) * 1000.0).round()),
            );
            self.out.push(f);
        }
    }

    /// 0x261–0x266 (and 0x481–0x486 when switched on), back to back.
    pub(crate) fn emit_low_rate(&mut self) {
        let voltage_dv = sat_u16((self.faults.voltage_v() * 10.0).round());
        for j in 0..6 {
            if self.faults.comm_lost(j) {
                continue;
            }
            let driver_t = self.faults.driver_temp_c(j, &self.motors[j]);
            let motor_t = self.faults.motor_temp_c(j, &self.motors[j]);
            // The joint motors have no bus-current sensing and report 0 (spec §4.6).
            let f = arm::encode_low_speed(
                j,
                voltage_dv,
                sat_i16(driver_t.round()),
                motor_t.round().clamp(-128.0, 127.0) as i8,
                self.driver_status_bits(j),
                0,
            );
            self.out.push(f);
        }
        self.emit_end_velocities();
    }

    /// 0x481–0x486: velocity and acceleration of each DH link frame, from finite differences
    /// over the 40 Hz period.
    fn emit_end_velocities(&mut self) {
        let frames = kin::link_frames(&self.reported_joints(), self.profile);
        let dt = STEP_S * LOW_RATE_DIVIDER as f64;
        if let Some(prev) = &self.prev_link_pose {
            let mut values = Vec::with_capacity(6);
            for j in 0..6 {
                let lin = (frames[j].translation.vector - prev[j].translation.vector).norm() / dt;
                let ang = frames[j].rotation.angle_to(&prev[j].rotation) / dt;
                let lin_acc = (lin - self.prev_link_vel[j][0]).abs() / dt;
                let ang_acc = (ang - self.prev_link_vel[j][1]).abs() / dt;
                self.prev_link_vel[j] = [lin, ang];
                values.push([lin, ang, lin_acc, ang_acc].map(|x| sat_u16((x * 1000.0).round())));
            }
            if self.periodic_48x {
                for (j, v) in values.into_iter().enumerate() {
                    self.out
                        .push(arm::encode_four_u16(ids::END_VEL_FIRST + j as u16, v));
                }
            }
        }
        self.prev_link_pose = Some(frames);
    }

    /// A leader arm's 0x151, 0x155–0x157 and 0x159 (spec §6.1, §8.3).
    pub(crate) fn emit_leader(&mut self) {
        let off = u16::from(self.flash.target_offset);
        let mode = ModeCtrl {
            ctrl_mode: CtrlMode::Can,
            move_mode: Some(MoveMode::J),
            speed_pct: 100,
            mit: Some(true),
            dwell_s: 0,
            install_position: 0,
        };
        self.out.push(hostc::encode_mode_ctrl(
            ids::MODE_CTRL + off,
            &mode,
            self.profile,
        ));
        let homing_alone = self.leader_homing
            == (LeaderHoming::Homing {
                with_follower: false,
            });
        if !homing_alone {
            let q: [i32; 6] = std::array::from_fn(|j| rad_to_mdeg(self.q_reported(j)));
            self.out
                .push(arm::encode_pair(ids::JOINT_12 + off, q[0], q[1]));
            self.out
                .push(arm::encode_pair(ids::JOINT_34 + off, q[2], q[3]));
            self.out
                .push(arm::encode_pair(ids::JOINT_56 + off, q[4], q[5]));
        }
        let travel = f64::from(self.flash.pendant_travel_pct.clamp(100, 200)) / 100.0;
        let g = GripperCtrl {
            stroke_um: sat_i32(f64::from(self.gripper_stroke_um()) * travel),
            effort_mnm: 1000,
            enable: true,
            clear_error: false,
            set_zero: false,
        };
        self.out
            .push(hostc::encode_gripper(ids::GRIPPER_CTRL + off, &g));
    }
}
