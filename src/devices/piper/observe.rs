//! A Piper's state as the driver sees it, in scenario units, for conditions and the trace.

use std::collections::BTreeMap;
use std::time::Duration;

use driver::piper::PiperState;

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

/// Feedback older than this counts as lost (10 feedback periods of 5 ms).
const FRESH: Duration = Duration::from_millis(50);

fn sorted(mut names: Vec<&'static str>) -> Vec<String> {
    names.sort_unstable();
    names.into_iter().map(str::to_owned).collect()
}

/// The harness's view of a driver state snapshot at tokio time `now`: the driver's SI
/// values in scenario units, status names from the driver's enums.
pub(crate) fn observe(state: &PiperState, now: tokio::time::Instant) -> Observation {
    let mut obs = Observation::default();
    if let Some(q) = state.joints_rad() {
        obs.joints_deg = q.iter().map(|a| a.to_degrees()).collect();
    }
    if state.high_speed.iter().any(Option::is_some) {
        let motors = || state.high_speed.iter().map(|h| h.as_ref().map(|h| h.value));
        obs.speeds_deg_s = motors()
            .map(|m| m.map_or(f64::NAN, |m| m.speed_rad_s.to_degrees()))
            .collect();
        obs.currents_a = motors()
            .map(|m| m.map_or(f64::NAN, |m| m.current_a))
            .collect();
    }
    if state.low_speed.iter().any(Option::is_some) {
        let drivers = || state.low_speed.iter().map(|l| l.as_ref().map(|l| l.value));
        obs.motor_temps_c = drivers()
            .map(|d| d.map_or(f64::NAN, |d| d.motor_temp_c))
            .collect();
        obs.enabled = drivers()
            .map(|d| d.is_some_and(|d| d.status.enabled()))
            .collect();
        obs.joint_flags = drivers()
            .map(|d| d.map_or_else(Vec::new, |d| sorted(d.status.faults())))
            .collect();
    }
    if let Some(p) = &state.end_pose {
        obs.position_mm = Some(p.value.position_m.map(|m| m * 1000.0));
        obs.orientation_deg = Some(p.value.orientation_rad.map(f64::to_degrees));
    }
    if let Some(g) = &state.gripper {
        obs.gripper_mm = Some(g.value.stroke_m * 1000.0);
        obs.gripper_enabled = Some(g.value.status.enabled());
        obs.gripper_flags = sorted(g.value.status.faults());
    }
    let mut status: BTreeMap<&'static str, String> = BTreeMap::new();
    if let Some(a) = &state.arm_status {
        let a = &a.value;
        obs.arm_status_code = Some(u8::from(a.status));
        status.insert("arm_status", a.status.to_string());
        status.insert("ctrl_mode", a.ctrl_mode.to_string());
        status.insert("move_mode", a.move_mode.to_string());
        status.insert("motion", a.motion.to_string());
        obs.comm_error_joints = a.comm_error.joints();
        obs.limit_error_joints = a.angle_limit_exceeded.joints();
    }
    let fresh = |at: Option<tokio::time::Instant>| {
        at.is_some_and(|at| now.saturating_duration_since(at) <= FRESH)
    };
    let joints_fresh = fresh(state.joints.as_ref().map(|j| j.received_at));
    status.insert(
        "feedback",
        if joints_fresh { "alive" } else { "lost" }.to_owned(),
    );
    let leader_fresh = fresh(state.joint_cmd_echo.as_ref().map(|j| j.received_at));
    status.insert("leader_frames", leader_fresh.to_string());
    obs.status = status;
    obs
}
