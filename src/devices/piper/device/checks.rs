//! Evaluate a Piper's conditions against its [`Observation`].

use crate::devices::piper::model::Check;
use crate::devices::piper::observe::Observation;

fn fmt1(v: f64) -> String {
    let text = format!("{v:.1}");
    if text == "-0.0" {
        "0.0".to_owned()
    } else {
        text
    }
}

fn list(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|v| fmt1(*v)).collect();
    format!("[{}]", parts.join(", "))
}

fn joints(values: &[u8]) -> String {
    let parts: Vec<String> = values.iter().map(u8::to_string).collect();
    format!("[{}]", parts.join(", "))
}

fn opt_list(values: &[Option<f64>]) -> String {
    let parts: Vec<String> = values
        .iter()
        .map(|v| v.map_or_else(|| "~".to_owned(), fmt1))
        .collect();
    format!("[{}]", parts.join(", "))
}

/// What a condition wants, for reports.
pub(in crate::devices::piper) fn expected_text(check: &Check) -> String {
    match check {
        Check::JointsNear {
            targets_deg,
            tolerance_deg,
        } => {
            format!("joints_deg {} ± {}", opt_list(targets_deg), tolerance_deg)
        }
        Check::JointsMin { bounds_deg } => format!("joints_deg >= {}", opt_list(bounds_deg)),
        Check::JointsMax { bounds_deg } => format!("joints_deg <= {}", opt_list(bounds_deg)),
        Check::MaxSpeed { deg_s } => format!("|joint speed| <= {deg_s} deg/s"),
        Check::MaxCurrent { amps } => format!("|motor current| <= {amps} A"),
        Check::PositionNear { mm, tolerance_mm } => {
            format!("position_mm {} ± {}", list(mm), tolerance_mm)
        }
        Check::OrientationNear { deg, tolerance_deg } => {
            format!("orientation_deg {} ± {}", list(deg), tolerance_deg)
        }
        Check::GripperNear { mm, tolerance_mm } => {
            format!("gripper_mm {} ± {}", fmt1(*mm), tolerance_mm)
        }
        Check::Status { field, value } => format!("{field} {value}"),
        Check::Enabled(e) => format!("enabled {e}"),
        Check::GripperEnabled(e) => format!("gripper_enabled {e}"),
        Check::EnabledJoints(j) => format!("enabled_joints {}", joints(j)),
        Check::CommErrorJoints(j) => format!("comm_error_joints {}", joints(j)),
        Check::LimitErrorJoints(j) => format!("limit_error_joints {}", joints(j)),
        Check::JointFaults { joint, flags } => {
            format!("joint {joint} faults [{}]", flags.join(", "))
        }
        Check::GripperFaults(flags) => format!("gripper_faults [{}]", flags.join(", ")),
    }
}

fn actual_text(check: &Check, obs: &Observation) -> String {
    let none = || "no feedback".to_owned();
    match check {
        Check::JointsNear { .. } | Check::JointsMin { .. } | Check::JointsMax { .. } => {
            if obs.joints_deg.is_empty() {
                none()
            } else {
                format!("joints_deg {}", list(&obs.joints_deg))
            }
        }
        Check::MaxSpeed { .. } => {
            if obs.speeds_deg_s.is_empty() {
                none()
            } else {
                format!("speeds_deg_s {}", list(&obs.speeds_deg_s))
            }
        }
        Check::MaxCurrent { .. } => {
            if obs.currents_a.is_empty() {
                none()
            } else {
                let parts: Vec<String> = obs.currents_a.iter().map(|c| format!("{c:.2}")).collect();
                format!("currents_a [{}]", parts.join(", "))
            }
        }
        Check::PositionNear { .. } => obs
            .position_mm
            .map_or_else(none, |p| format!("position_mm {}", list(&p))),
        Check::OrientationNear { .. } => obs
            .orientation_deg
            .map_or_else(none, |p| format!("orientation_deg {}", list(&p))),
        Check::GripperNear { .. } => obs
            .gripper_mm
            .map_or_else(none, |g| format!("gripper_mm {}", fmt1(g))),
        Check::Status { field, .. } => format!(
            "{field} {}",
            obs.status.get(field).cloned().unwrap_or_else(none)
        ),
        Check::EnabledJoints(_) => format!("enabled_joints {}", joints(&enabled_list(obs))),
        Check::Enabled(_) => {
            let parts: Vec<&str> = obs
                .enabled
                .iter()
                .map(|e| if *e { "1" } else { "0" })
                .collect();
            format!("enable bits [{}]", parts.join(", "))
        }
        Check::GripperEnabled(_) => obs
            .gripper_enabled
            .map_or_else(none, |e| format!("gripper_enabled {e}")),
        Check::CommErrorJoints(_) => {
            format!("comm_error_joints {}", joints(&obs.comm_error_joints))
        }
        Check::LimitErrorJoints(_) => {
            format!("limit_error_joints {}", joints(&obs.limit_error_joints))
        }
        Check::JointFaults { joint, .. } => match obs.joint_flags.get(usize::from(*joint) - 1) {
            Some(flags) => format!("joint {joint} faults [{}]", flags.join(", ")),
            None => none(),
        },
        Check::GripperFaults(_) => format!("gripper_faults [{}]", obs.gripper_flags.join(", ")),
    }
}

fn per_joint(values: &[f64], wanted: &[Option<f64>], ok: impl Fn(f64, f64) -> bool) -> bool {
    if values.len() < wanted.len() {
        return false;
    }
    values
        .iter()
        .zip(wanted)
        .all(|(v, w)| w.is_none_or(|w| ok(*v, w)))
}

fn holds(check: &Check, obs: &Observation) -> bool {
    match check {
        Check::JointsNear {
            targets_deg,
            tolerance_deg,
        } => per_joint(&obs.joints_deg, targets_deg, |v, w| {
            (v - w).abs() <= *tolerance_deg
        }),
        Check::JointsMin { bounds_deg } => per_joint(&obs.joints_deg, bounds_deg, |v, w| v >= w),
        Check::JointsMax { bounds_deg } => per_joint(&obs.joints_deg, bounds_deg, |v, w| v <= w),
        Check::MaxSpeed { deg_s } => {
            !obs.speeds_deg_s.is_empty() && obs.speeds_deg_s.iter().all(|s| s.abs() <= *deg_s)
        }
        Check::MaxCurrent { amps } => {
            !obs.currents_a.is_empty() && obs.currents_a.iter().all(|c| c.abs() <= *amps)
        }
        Check::PositionNear { mm, tolerance_mm } => obs.position_mm.is_some_and(|p| {
            p.iter()
                .zip(mm)
                .all(|(a, b)| (a - b).abs() <= *tolerance_mm)
        }),
        Check::OrientationNear { deg, tolerance_deg } => obs.orientation_deg.is_some_and(|p| {
            p.iter()
                .zip(deg)
                .all(|(a, b)| angle_diff(*a, *b) <= *tolerance_deg)
        }),
        Check::GripperNear { mm, tolerance_mm } => obs
            .gripper_mm
            .is_some_and(|g| (g - mm).abs() <= *tolerance_mm),
        Check::Status { field, value } => obs.status.get(field) == Some(value),
        Check::Enabled(e) => !obs.enabled.is_empty() && obs.enabled.iter().all(|b| b == e),
        Check::GripperEnabled(e) => obs.gripper_enabled == Some(*e),
        Check::EnabledJoints(j) => !obs.enabled.is_empty() && enabled_list(obs) == *j,
        Check::CommErrorJoints(j) => obs.comm_error_joints == *j,
        Check::LimitErrorJoints(j) => obs.limit_error_joints == *j,
        Check::JointFaults { joint, flags } => obs
            .joint_flags
            .get(usize::from(*joint) - 1)
            .is_some_and(|f| f == flags),
        Check::GripperFaults(flags) => obs.gripper_flags == *flags,
    }
}

fn enabled_list(obs: &Observation) -> Vec<u8> {
    obs.enabled
        .iter()
        .enumerate()
        .filter(|(_, e)| **e)
        .filter_map(|(i, _)| u8::try_from(i + 1).ok())
        .collect()
}

/// Difference of two angles in degrees, wrapped to 0..=180.
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// `Ok` when the condition holds, else `(expected, actual)`.
pub(super) fn evaluate_one(check: &Check, obs: &Observation) -> Result<(), (String, String)> {
    if holds(check, obs) {
        Ok(())
    } else {
        Err((expected_text(check), actual_text(check, obs)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs_with_joints(j: [f64; 6]) -> Observation {
        Observation {
            joints_deg: j.to_vec(),
            ..Observation::default()
        }
    }

    #[test]
    fn joints_near_respects_tolerance_and_skips_none() {
        let check = Check::JointsNear {
            targets_deg: vec![Some(90.0), None, None, None, None, Some(0.0)],
            tolerance_deg: 0.5,
        };
        assert!(holds(
            &check,
            &obs_with_joints([90.4, 33.0, 0.0, 0.0, 0.0, -0.2])
        ));
        let err = evaluate_one(&check, &obs_with_joints([89.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
        let (expected, actual) = err.expect_err("89.0 is 1° off");
        assert_eq!(expected, "joints_deg [90.0, ~, ~, ~, ~, 0.0] ± 0.5");
        assert_eq!(actual, "joints_deg [89.0, 0.0, 0.0, 0.0, 0.0, 0.0]");
    }

    #[test]
    fn missing_feedback_never_satisfies() {
        let check = Check::MaxSpeed { deg_s: 1.0 };
        assert!(!holds(&check, &Observation::default()));
        assert!(!holds(&Check::Enabled(false), &Observation::default()));
    }

    #[test]
    fn orientation_wraps_around() {
        assert!(angle_diff(179.9, -179.9) < 0.3);
    }
}
