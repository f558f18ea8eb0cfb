//! Timestamped state snapshots built from the decoded feedback. Snapshots are plain copies:
//! callers never share mutable state with the receive task.

use std::collections::BTreeMap;
use std::time::Duration;

use tokio::time::Instant;

use super::codec::{self, si, EndPosePart, FirmwareInfo, JointMask, JointPair, Message};
use super::types::{
    ArmStatus, DriverState, EndLimits, EndMotion, EndPose, GripperCommand, GripperState,
    GripperTeachParams, JointLimits, LeaderMode, MotorState,
};

/// A value with the time it arrived.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Stamped<T> {
    /// The value.
    pub value: T,
    /// The bus timestamp of the (last) frame that carried it.
    pub bus_time: Duration,
    /// Local (tokio, virtual in tests) time of reception.
    #[serde(skip)]
    pub received_at: Instant,
    /// Running count of updates of this value since connect.
    pub seq: u64,
}

fn stamp<T>(slot: &mut Option<Stamped<T>>, value: T, bus_time: Duration, now: Instant) {
    let seq = slot.as_ref().map_or(1, |s| s.seq + 1);
    *slot = Some(Stamped {
        value,
        bus_time,
        received_at: now,
        seq,
    });
}

/// Joint angles J1–J6 in rad (feedback 0x2A5–0x2A7 or a leader's 0x155–0x157).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct JointAngles {
    /// Angles of joints 1–6, rad.
    pub rad: [f64; 6],
}

impl JointAngles {
    fn apply(&mut self, pair: &JointPair) {
        let first = usize::from(pair.first_joint.clamp(1, 5)) - 1;
        self.rad[first] = si::mdeg_to_rad(pair.a_mdeg);
        self.rad[first + 1] = si::mdeg_to_rad(pair.b_mdeg);
    }
}

/// Why the bus link is not healthy.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub enum BusFault {
    /// The controller is bus-off.
    BusOff,
    /// The interface is down.
    InterfaceDown,
    /// The bus endpoint was closed underneath the driver.
    Closed,
    /// The transmit queue is full (frames are not leaving).
    TxQueueFull,
    /// An operating-system error, with its message.
    Io(String),
}

/// Link health: freshness of the feedback and message rates.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct LinkHealth {
    /// Feedback seen within the link timeout and no bus fault (updated every monitor tick).
    pub ok: bool,
    /// Local time of the last decoded frame from the arm.
    #[serde(skip)]
    pub last_feedback: Option<Instant>,
    /// Frames received since connect (all ids).
    pub frames_total: u64,
    /// Frames that failed to decode.
    pub malformed: u64,
    /// Frames dropped by the abnormal-data filter.
    pub filtered: u64,
    /// Received frames per second over the last second.
    pub frames_per_s: f64,
    /// Per-CAN-id rate in Hz over the last second.
    pub rates_hz: BTreeMap<u16, f64>,
    /// The current bus fault, if any.
    pub bus_fault: Option<BusFault>,
    /// Times the driver re-opened the bus.
    pub reconnects: u64,
}

/// A snapshot of everything the driver knows about the arm.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct PiperState {
    /// 0x2A1 arm status (decoded fault bits inside).
    pub arm_status: Option<Stamped<ArmStatus>>,
    /// 0x2A2–0x2A4 flange pose.
    pub end_pose: Option<Stamped<EndPose>>,
    /// 0x2A5–0x2A7 joint angles.
    pub joints: Option<Stamped<JointAngles>>,
    /// 0x2A8 gripper.
    pub gripper: Option<Stamped<GripperState>>,
    /// 0x251–0x256 per joint (index 0 = joint 1).
    pub high_speed: [Option<Stamped<MotorState>>; 6],
    /// 0x261–0x266 per joint (index 0 = joint 1).
    pub low_speed: [Option<Stamped<DriverState>>; 6],
    /// 0x481–0x486 per joint, when switched on.
    pub end_vel_acc: [Option<Stamped<EndMotion>>; 6],
    /// 0x151 seen on the bus (a leader arm's mode).
    pub mode_echo: Option<Stamped<LeaderMode>>,
    /// 0x155–0x157 seen on the bus (a leader arm's joints).
    pub joint_cmd_echo: Option<Stamped<JointAngles>>,
    /// 0x159 seen on the bus (a leader arm's gripper).
    pub gripper_cmd_echo: Option<Stamped<GripperCommand>>,
    /// Last firmware reply.
    pub firmware: Option<FirmwareInfo>,
    /// Last 0x473 reply per joint.
    pub joint_limits: [Option<JointLimits>; 6],
    /// Last 0x47C reply per joint: max acceleration, rad/s².
    pub joint_max_acc_rad_s2: [Option<f64>; 6],
    /// Last 0x478 reply.
    pub end_limits: Option<EndLimits>,
    /// Last 0x47B reply: collision-protection level 0–8 per joint.
    pub collision_levels: Option<[u8; 6]>,
    /// Last 0x47E reply.
    pub gripper_teach: Option<GripperTeachParams>,
    /// The command of the last 0x476 acknowledgement.
    pub last_ack: Option<Stamped<codec::AckedCommand>>,
    /// Link health.
    pub link: LinkHealth,
}

impl PiperState {
    /// Joints whose last low-speed frame has the driver-enabled bit.
    pub fn enabled_mask(&self) -> JointMask {
        let mut mask = 0u8;
        for (i, slot) in self.low_speed.iter().enumerate() {
            if slot.as_ref().is_some_and(|s| s.value.status.enabled()) {
                mask |= 1 << i;
            }
        }
        JointMask(mask)
    }

    /// True when all six joints report enabled (the SDKs' `GetArmEnableStatus`).
    pub fn arm_enabled(&self) -> bool {
        self.enabled_mask() == JointMask::ALL
    }

    /// Driver status bits of joint 1–6, if seen.
    pub fn driver_status(&self, joint: u8) -> Option<codec::DriverStatus> {
        let index = usize::from(joint.checked_sub(1)?);
        self.low_speed.get(index)?.as_ref().map(|s| s.value.status)
    }

    /// Joint angles in rad, if seen.
    pub fn joints_rad(&self) -> Option<[f64; 6]> {
        self.joints.as_ref().map(|j| j.value.rad)
    }

    /// Gripper stroke in m, if seen.
    pub fn gripper_stroke_m(&self) -> Option<f64> {
        self.gripper.as_ref().map(|g| g.value.stroke_m)
    }

    /// Motor speeds in rad/s (None for joints not seen).
    pub fn joint_speeds_rad_s(&self) -> [Option<f64>; 6] {
        self.high_speed.map(|h| h.map(|h| h.value.speed_rad_s))
    }

    /// Apply one decoded codec message received at bus time `bus_time` and local time `now`
    /// (what the receive task does for every frame; public for tools and benchmarks that
    /// decode recordings). Returns false for messages that carry no state.
    pub fn apply(&mut self, message: &Message, bus_time: Duration, now: Instant) -> bool {
        match message {
            Message::ArmStatus(s) => stamp(&mut self.arm_status, si::arm_status(s), bus_time, now),
            Message::EndPose(part) => {
                let mut pose = self.end_pose.map(|p| p.value).unwrap_or_default();
                si::apply_end_pose(&mut pose, part);
                stamp(&mut self.end_pose, pose, bus_time, now);
            }
            Message::Joints(pair) => {
                let mut joints = self.joints.map(|j| j.value).unwrap_or_default();
                joints.apply(pair);
                stamp(&mut self.joints, joints, bus_time, now);
            }
            Message::Gripper(g) => stamp(&mut self.gripper, si::gripper_state(g), bus_time, now),
            Message::HighSpeed(h) => {
                if let Some(slot) = joint_slot(&mut self.high_speed, h.joint) {
                    stamp(slot, si::motor_state(h), bus_time, now);
                }
            }
            Message::LowSpeed(l) => {
                if let Some(slot) = joint_slot(&mut self.low_speed, l.joint) {
                    stamp(slot, si::driver_state(l), bus_time, now);
                }
            }
            Message::EndVelAcc(e) => {
                if let Some(slot) = joint_slot(&mut self.end_vel_acc, e.joint) {
                    stamp(slot, si::end_motion(e), bus_time, now);
                }
            }
            Message::ModeEcho(m) => stamp(&mut self.mode_echo, si::leader_mode(m), bus_time, now),
            Message::JointCmdEcho(pair) => {
                let mut joints = self.joint_cmd_echo.map(|j| j.value).unwrap_or_default();
                joints.apply(pair);
                stamp(&mut self.joint_cmd_echo, joints, bus_time, now);
            }
            Message::GripperCmdEcho(g) => stamp(
                &mut self.gripper_cmd_echo,
                si::gripper_command(g),
                bus_time,
                now,
            ),
            Message::JointLimits(l) => {
                if let Some(slot) = joint_slot(&mut self.joint_limits, l.joint) {
                    *slot = Some(si::joint_limits(l));
                }
            }
            Message::JointMaxAcc(a) => {
                if let Some(slot) = joint_slot(&mut self.joint_max_acc_rad_s2, a.joint) {
                    *slot = Some(si::max_acc(a.max_acc_crad_s2));
                }
            }
            Message::Ack(a) => stamp(&mut self.last_ack, a.cmd, bus_time, now),
            Message::EndParams(p) => self.end_limits = Some(si::end_limits(p)),
            Message::Collision(c) => self.collision_levels = Some(c.levels),
            Message::GripperTeach(g) => self.gripper_teach = Some(si::gripper_teach(g)),
            Message::Assist(_) | Message::FirmwarePart(_) | Message::Cpv(_) => return false,
        }
        true
    }
}

fn joint_slot<T>(slots: &mut [Option<T>; 6], joint: u8) -> Option<&mut Option<T>> {
    slots.get_mut(usize::from(joint.checked_sub(1)?))
}

/// The SDK's "abnormal data" filter (spec §11): true when the message carries values no real
/// arm reports (|X|,|Y|,|Z| > 1 m; |angle| > 361°; |joint| > 3000°; |stroke| > 150 mm) and
/// must be dropped.
pub(crate) fn is_abnormal(message: &Message) -> bool {
    const MAX_POS_UM: i32 = 1_000_000;
    const MAX_ROT_MDEG: i32 = 361_000;
    const MAX_JOINT_MDEG: i32 = 3_000_000;
    const MAX_STROKE_UM: i32 = 150_000;
    let over = |v: i32, max: i32| v.unsigned_abs() > max.unsigned_abs();
    match *message {
        Message::EndPose(EndPosePart::Xy { x_um, y_um }) => {
            over(x_um, MAX_POS_UM) || over(y_um, MAX_POS_UM)
        }
        Message::EndPose(EndPosePart::ZRx { z_um, rx_mdeg }) => {
            over(z_um, MAX_POS_UM) || over(rx_mdeg, MAX_ROT_MDEG)
        }
        Message::EndPose(EndPosePart::RyRz { ry_mdeg, rz_mdeg }) => {
            over(ry_mdeg, MAX_ROT_MDEG) || over(rz_mdeg, MAX_ROT_MDEG)
        }
        Message::Joints(pair) => {
            over(pair.a_mdeg, MAX_JOINT_MDEG) || over(pair.b_mdeg, MAX_JOINT_MDEG)
        }
        Message::Gripper(g) => over(g.stroke_um, MAX_STROKE_UM),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::piper::codec::{decode, GripperStatus};
    use bus::CanFrame;

    fn message(id: u16, data: &[u8]) -> Message {
        match CanFrame::standard(id, data).map(|f| decode(&f)) {
            Ok(Ok(Some(message))) => message,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn joint_frames_merge_into_one_snapshot_with_sequence_numbers() {
        let mut state = PiperState::default();
        let now = Instant::now();
        let a = message(0x2A5, &[0, 1, 0x5F, 0x90, 0xFF, 0xFE, 0xA0, 0x70]);
        let b = message(0x2A7, &[0, 0, 0, 1, 0, 0, 0, 2]);
        assert!(state.apply(&a, Duration::from_millis(1), now));
        assert!(state.apply(&b, Duration::from_millis(2), now));
        let joints = state.joints.expect("joints");
        let expected = [90_000, -90_000, 0, 0, 1, 2].map(si::mdeg_to_rad);
        assert_eq!(joints.value.rad, expected);
        assert_eq!((joints.seq, joints.bus_time), (2, Duration::from_millis(2)));
        let rad = state.joints_rad().expect("rad");
        assert!((rad[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn enable_mask_comes_from_bit_6_of_each_low_speed_frame() {
        let mut state = PiperState::default();
        let now = Instant::now();
        for joint in 1..=6u16 {
            let status = if joint == 4 { 0x00 } else { 0x40 };
            state.apply(
                &message(0x260 + joint, &[1, 0xE0, 0, 25, 25, status, 0, 0]),
                Duration::ZERO,
                now,
            );
        }
        assert_eq!(state.enabled_mask().0, 0b11_0111);
        assert!(!state.arm_enabled());
        assert_eq!(state.driver_status(4).map(|s| s.enabled()), Some(false));
        assert_eq!(state.driver_status(7), None);
    }

    #[test]
    fn abnormal_filter_uses_the_sdk_thresholds() {
        assert!(!is_abnormal(&message(
            0x2A5,
            &[0, 0x2D, 0xC6, 0xC0, 0, 0, 0, 0]
        ))); // 3_000_000
        assert!(is_abnormal(&message(
            0x2A5,
            &[0, 0x2D, 0xC6, 0xC1, 0, 0, 0, 0]
        ))); // 3_000_001
        assert!(is_abnormal(&message(
            0x2A2,
            &[0xFF, 0xF0, 0xBD, 0xBF, 0, 0, 0, 0]
        ))); // −1_000_001
        assert!(is_abnormal(&message(
            0x2A4,
            &[0, 0x05, 0x82, 0x29, 0, 0, 0, 0]
        ))); // 361_001
        assert!(is_abnormal(&message(
            0x2A8,
            &[0, 0x02, 0x49, 0xF1, 0, 0, 0x40, 0]
        ))); // 150_001
        assert!(!is_abnormal(&message(
            0x2A8,
            &[0, 0x02, 0x49, 0xF0, 0, 0, 0x40, 0]
        )));
        let g = GripperStatus(0x40);
        assert!(g.enabled() && !g.homed());
    }
}
