//! The arm as the driver sees it (the latest push sample, the push rate, the connections) and
//! the conditions judged against it; its trace columns are in [`super::trace`].

use driver::realman::{ArmState, ArmStatus};

use super::model::{RmCond, ARM_STATES, ERRORS};

/// What the driver knows now.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Observation {
    /// Joint angles, degrees (`None` before the first push sample).
    pub joints_deg: Option<Vec<f64>>,
    /// Joint speeds, °/s (when the push carries them).
    pub speeds_deg_s: Option<Vec<f64>>,
    /// Joint currents, A.
    pub currents_a: Option<Vec<f64>>,
    /// Joint temperatures, °C.
    pub temperatures_c: Option<Vec<f64>>,
    /// Tool position, m, and Euler angles, degrees.
    pub pose: Option<([f64; 3], [f64; 3])>,
    /// The push's `arm_current_status` name.
    pub arm_state: Option<&'static str>,
    /// Controller errors by name ([`ERRORS`] order; unknown codes as `0x....`).
    pub errors: Vec<String>,
    /// First error code (0 = none).
    pub first_error: Option<u32>,
    /// Per-joint enable flags.
    pub enabled: Option<Vec<bool>>,
    /// Push datagrams in the last second.
    pub push_hz: f64,
    /// Every driver connection up.
    pub connected: bool,
}

/// The scenario name of a push status.
fn state_name(status: &ArmStatus) -> Option<&'static str> {
    ARM_STATES
        .iter()
        .find(|n| ArmStatus::from_wire(n) == *status)
        .copied()
}

impl Observation {
    /// Fill from a push sample.
    pub fn from_sample(s: &ArmState, push_hz: f64, connected: bool) -> Self {
        let deg = |v: &[f64]| v.iter().map(|r| r.to_degrees()).collect::<Vec<_>>();
        let codes: Vec<u32> = s.errors.iter().map(|e| e.code()).collect();
        let mut errors: Vec<String> = ERRORS
            .iter()
            .filter(|(_, c)| codes.contains(c))
            .map(|(n, _)| (*n).to_owned())
            .collect();
        errors.extend(
            codes
                .iter()
                .filter(|c| !ERRORS.iter().any(|(_, k)| k == *c))
                .map(|c| format!("0x{c:04X}")),
        );
        Self {
            joints_deg: Some(deg(&s.joints_rad)),
            speeds_deg_s: s.joint_speeds_rad_s.as_deref().map(deg),
            currents_a: Some(s.currents_a.clone()),
            temperatures_c: Some(s.temperatures_c.clone()),
            pose: Some((s.pose.position_m, s.pose.euler_rad.map(f64::to_degrees))),
            arm_state: s.status.as_ref().and_then(state_name),
            errors,
            first_error: Some(codes.first().copied().unwrap_or(0)),
            enabled: Some(s.enabled.clone()),
            push_hz,
            connected,
        }
    }
}

fn list(v: &[f64], digits: usize) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:.digits$}")).collect();
    format!("[{}]", items.join(", "))
}

impl RmCond {
    /// What the condition wants, for reports.
    pub fn expected_text(&self) -> String {
        match self {
            Self::Joints(j, t) => format!("joints_deg {} ± {t}", list(j, 2)),
            Self::Position(p, t) => format!("position_m {} within {t}", list(p, 4)),
            Self::ArmState(s) => format!("arm_state {s}"),
            Self::Errors(e) => format!("errors [{}]", e.join(", ")),
            Self::Enabled(e) => format!("joints_enabled {e:?}"),
            Self::PushHz(n) => format!("push_hz {} ± {}", n.value, n.tolerance),
            Self::Connected(c) => format!("connected {c}"),
        }
    }

    /// What the arm shows for this condition.
    pub fn actual_text(&self, o: &Observation) -> String {
        let unknown = || "unknown (no push sample yet)".to_owned();
        match self {
            Self::Joints(..) => o
                .joints_deg
                .as_ref()
                .map_or_else(unknown, |j| format!("joints_deg {}", list(j, 2))),
            Self::Position(..) => o
                .pose
                .map_or_else(unknown, |(p, _)| format!("position_m {}", list(&p, 4))),
            Self::ArmState(_) => format!("arm_state {}", o.arm_state.unwrap_or("unknown")),
            Self::Errors(_) => format!("errors [{}]", o.errors.join(", ")),
            Self::Enabled(_) => o
                .enabled
                .as_ref()
                .map_or_else(unknown, |e| format!("joints_enabled {e:?}")),
            Self::PushHz(_) => format!("push_hz {}", o.push_hz),
            Self::Connected(_) => format!("connected {}", o.connected),
        }
    }

    /// Whether the condition holds.
    pub fn holds(&self, o: &Observation) -> bool {
        match self {
            Self::Joints(want, t) => o.joints_deg.as_ref().is_some_and(|j| {
                j.len() == want.len() && j.iter().zip(want).all(|(a, b)| (a - b).abs() <= *t)
            }),
            Self::Position(want, t) => o.pose.is_some_and(|(p, _)| {
                p.iter()
                    .zip(want)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    <= *t
            }),
            Self::ArmState(s) => o.arm_state == Some(*s),
            Self::Errors(e) => o.joints_deg.is_some() && o.errors == *e,
            Self::Enabled(e) => o.enabled.as_ref() == Some(e),
            Self::PushHz(n) => (o.push_hz - n.value).abs() <= n.tolerance,
            Self::Connected(c) => o.connected == *c,
        }
    }
}
