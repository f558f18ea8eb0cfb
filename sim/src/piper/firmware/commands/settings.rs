//! Configuration commands and queries: flash settings (limits, offsets, collision levels,
//! end-effector limits, gripper teach), motor parameters, the identity query.

use crate::piper::codec::arm::{self, FirmwareInfo};
use crate::piper::codec::host::{
    CtrlMode, EndVelAcc, LinkageConfig, LinkageRole as WireRole, ParamQuery,
};
use crate::piper::firmware::Firmware;
use crate::piper::flash::{
    rules as flash_rules, LinkageRole, DEFAULT_END_VEL_ACC, MAX_ACC_CEILING_CRAD_S2,
    MAX_SPEED_CEILING_CRAD_S,
};
use crate::piper::ids;

/// Identity strings of the 0x4AF reply other than the software version.
const HARDWARE_VERSION: &str = "H-V1.2-1";
const MOTOR_RATIO: &str = "10";
const NODE_TYPE: &str = "ARM_MC";
const PRODUCTION_DATE: &str = "250925";
const NODE_NUMBER: &str = "15";

/// Minimum delay of the 0x4AF reply, ms. piper_sdk clears its firmware buffer *after* sending
/// the query, so an instant reply could be wiped; its README waits ~25 ms for the answer.
pub(super) const FIRMWARE_REPLY_DELAY_MS: u64 = 5;

impl Firmware {
    /// 0x181–0x187 (CPV): write or read a motor parameter; both answer with its value.
    pub(super) fn on_cpv(&mut self, motor: u8, mode: u8, param: [u8; 2], value: i32) {
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

    /// 0x470: leader/follower role and the three ID offsets.
    pub(super) fn on_linkage(&mut self, cfg: LinkageConfig) {
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

    /// 0x472: one joint's limits or its acceleration limit, answered at once.
    pub(super) fn on_joint_query(&mut self, joint: usize, acceleration: bool) {
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

    /// 0x474: a joint's angle limits and speed limit; an inverted range is ignored.
    pub(super) fn on_set_joint_limits(
        &mut self,
        joint: usize,
        max_angle_ddeg: Option<i16>,
        min_angle_ddeg: Option<i16>,
        max_speed_crad_s: Option<u16>,
    ) {
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

    /// 0x475: zero a joint (disabled joints only), its acceleration limit, clear its error.
    pub(super) fn on_joint_config(
        &mut self,
        joint: Option<usize>,
        set_zero: bool,
        max_acc_crad_s2: Option<u16>,
        clear_error: bool,
    ) {
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

    /// 0x477: parameter queries, resets, the 0x48x switch and the payload.
    pub(super) fn on_param_query(&mut self, p: ParamQuery) {
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

    /// 0x479: end-effector speed and acceleration limits (unchanged fields kept).
    pub(super) fn on_set_end_vel_acc(&mut self, e: EndVelAcc) {
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

    /// 0x47A: collision protection levels (unchanged joints kept).
    pub(super) fn on_set_collision(&mut self, levels: [Option<u8>; 6]) {
        for (slot, l) in self.flash.collision_levels.iter_mut().zip(levels) {
            if let Some(l) = l {
                *slot = l;
            }
        }
        self.mark_flash_dirty();
        self.out.push(arm::encode_ack(0x7A, false, 0));
    }

    /// 0x47D: teach pendant travel, gripper stroke and friction.
    pub(super) fn on_set_gripper_teach(&mut self, travel_pct: u8, max_stroke_mm: u8, friction: u8) {
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

    /// 0x4AF query: the identity strings, sent after a short delay.
    pub(super) fn on_firmware_query(&mut self) {
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
