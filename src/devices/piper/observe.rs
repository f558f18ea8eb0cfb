//! A Piper's state as the driver sees it, in scenario units, for conditions and the trace.

use std::collections::BTreeMap;

/// A Piper's state in physical units. Empty vectors / `None` mean "not known yet" (no feedback
/// received).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Observation {
    /// Joint angles.
    pub joints_deg: Vec<f64>,
    /// Joint speeds.
    pub speeds_deg_s: Vec<f64>,
    /// Motor currents.
    pub currents_a: Vec<f64>,
    /// Motor temperatures.
    pub motor_temps_c: Vec<f64>,
    /// Flange position.
    pub position_mm: Option<[f64; 3]>,
    /// Flange orientation.
    pub orientation_deg: Option<[f64; 3]>,
    /// Gripper stroke.
    pub gripper_mm: Option<f64>,
    /// Named status values (`arm_status`, `ctrl_mode`, `move_mode`, `motion`, `feedback`,
    /// `leader_frames`).
    pub status: BTreeMap<&'static str, String>,
    /// Raw arm status code (for the trace).
    pub arm_status_code: Option<u8>,
    /// Per-joint enable bits.
    pub enabled: Vec<bool>,
    /// Gripper enable bit.
    pub gripper_enabled: Option<bool>,
    /// Joints with the comm-error bit set.
    pub comm_error_joints: Vec<u8>,
    /// Joints with the angle-limit bit set.
    pub limit_error_joints: Vec<u8>,
    /// Per-joint driver fault flags (sorted names).
    pub joint_flags: Vec<Vec<String>>,
    /// Gripper fault flags (sorted names).
    pub gripper_flags: Vec<String>,
}
