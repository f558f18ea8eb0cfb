//! What [`super::PiperHandle::snapshot`] returns: the simulation's ground truth.

use super::flash::Flash;
use super::pose::WirePose;

/// Status as the firmware would report it, decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmStatusSnapshot {
    /// 0x2A1 byte 0.
    pub ctrl_mode: u8,
    /// 0x2A1 byte 1.
    pub arm_status: u8,
    /// 0x2A1 byte 2.
    pub mode_feed: u8,
    /// 0x2A1 byte 4.
    pub motion_status: u8,
    /// 0x2A1 byte 6.
    pub limit_bits: u8,
    /// 0x2A1 byte 7.
    pub comm_bits: u8,
    /// 0x26x byte 5 bit 6 per joint.
    pub enabled: [bool; 6],
    /// 0x2A8 byte 6 bit 6.
    pub gripper_enabled: bool,
    /// 0x26x byte 5 per joint.
    pub driver_status: [u8; 6],
}

/// True state of the emulated arm at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct PiperSimState {
    /// Simulated time since boot, s.
    pub time_s: f64,
    /// Physical joint angles in the physics world, rad.
    pub joint_positions_rad: [f64; 6],
    /// Angles the firmware reports (physical minus zero offsets), rad.
    pub reported_joints_rad: [f64; 6],
    /// Joint velocities, rad/s.
    pub joint_velocities_rad_s: [f64; 6],
    /// Torque each motor produced in the last step, N·m.
    pub joint_torques_nm: [f64; 6],
    /// Motor currents, A.
    pub motor_currents_a: [f64; 6],
    /// Motor winding temperatures as reported, °C.
    pub motor_temps_c: [f64; 6],
    /// Gripper opening in the physics world, m.
    pub gripper_stroke_m: f64,
    /// Finger force the gripper motor produced, N.
    pub gripper_force_n: f64,
    /// Flange pose by the firmware's DH model.
    pub flange_pose: WirePose,
    /// Number of arm–obstacle contacts.
    pub contacts: usize,
    /// Status bytes.
    pub status: ArmStatusSnapshot,
    /// Current flash parameters.
    pub flash: Flash,
}
