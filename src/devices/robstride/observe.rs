//! RobStride motors as the driver sees them: the last status frame (type 2 reply or type 24
//! active report) and the last type-21 fault report of each CAN ID, and the per-motor
//! conditions judged against them.

use std::collections::BTreeMap;

use driver::robstride::{FaultReport, Feedback, FeedbackKind, MotorMode};

use super::model::{MotorCond, REPORT_FLAGS, STATUS_FAULTS};
use crate::devices::contract::motor_bus::fixed;
use crate::scenario::Near;

/// Every motor of the bus by CAN ID.
pub type Observation = BTreeMap<u8, MotorObservation>;

/// One motor as the driver last saw it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MotorObservation {
    /// Last status frame (`None` before the first one).
    pub angle_rad: Option<f64>,
    /// Speed.
    pub speed_rad_s: Option<f64>,
    /// Torque.
    pub torque_nm: Option<f64>,
    /// Temperature.
    pub temperature_c: Option<f64>,
    /// Mode state name ([`MODE_STATES`](super::model::MODE_STATES)).
    pub mode_state: Option<&'static str>,
    /// Set status-frame fault bits ([`STATUS_FAULTS`](super::model::STATUS_FAULTS)).
    pub status_faults: Vec<&'static str>,
    /// Set flags of the last type-21 report ([`REPORT_FLAGS`](super::model::REPORT_FLAGS)), empty when none came.
    pub fault_report: Vec<&'static str>,
    /// Kind of the last status frame ([`FEEDBACK_KINDS`](super::model::FEEDBACK_KINDS)).
    pub feedback: Option<&'static str>,
}

/// `v` with 2 decimals, never `-0.00`.
pub(super) fn f2(v: f64) -> String {
    fixed(v, 2)
}

pub(super) fn near_text(n: &Near) -> String {
    format!("{} ± {}", f2(n.value), f2(n.tolerance))
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "unknown".to_owned(), f2)
}

impl MotorCond {
    /// What the condition wants, for reports.
    pub fn expected_text(&self, motor: u8) -> String {
        let what = match self {
            Self::Position(n) => format!("position_rad {}", near_text(n)),
            Self::Velocity(n) => format!("velocity_rad_s {}", near_text(n)),
            Self::Torque(n) => format!("torque_nm {}", near_text(n)),
            Self::TempMin(t) => format!("temp_c >= {}", f2(*t)),
            Self::TempMax(t) => format!("temp_c <= {}", f2(*t)),
            Self::ModeState(m) => format!("mode_state {m}"),
            Self::StatusFaults(f) => format!("faults [{}]", f.join(", ")),
            Self::FaultReport(f) => format!("fault_report [{}]", f.join(", ")),
            Self::Feedback(k) => format!("feedback {k}"),
        };
        format!("motor {motor} {what}")
    }

    /// What the motor shows for this condition, for reports.
    pub fn actual_text(&self, motor: u8, obs: &Observation) -> String {
        let Some(m) = obs.get(&motor) else {
            return format!("motor {motor} not on the bus");
        };
        let what = match self {
            Self::Position(_) => format!("position_rad {}", opt(m.angle_rad)),
            Self::Velocity(_) => format!("velocity_rad_s {}", opt(m.speed_rad_s)),
            Self::Torque(_) => format!("torque_nm {}", opt(m.torque_nm)),
            Self::TempMin(_) | Self::TempMax(_) => format!("temp_c {}", opt(m.temperature_c)),
            Self::ModeState(_) => format!("mode_state {}", m.mode_state.unwrap_or("unknown")),
            Self::StatusFaults(_) => format!("faults [{}]", m.status_faults.join(", ")),
            Self::FaultReport(_) => format!("fault_report [{}]", m.fault_report.join(", ")),
            Self::Feedback(_) => format!("feedback {}", m.feedback.unwrap_or("none")),
        };
        format!("motor {motor} {what}")
    }

    /// Whether the condition holds.
    pub fn holds(&self, motor: u8, obs: &Observation) -> bool {
        let Some(m) = obs.get(&motor) else {
            return false;
        };
        let near = |v: Option<f64>, n: &Near| v.is_some_and(|v| (v - n.value).abs() <= n.tolerance);
        match self {
            Self::Position(n) => near(m.angle_rad, n),
            Self::Velocity(n) => near(m.speed_rad_s, n),
            Self::Torque(n) => near(m.torque_nm, n),
            Self::TempMin(t) => m.temperature_c.is_some_and(|v| v >= *t),
            Self::TempMax(t) => m.temperature_c.is_some_and(|v| v <= *t),
            Self::ModeState(s) => m.mode_state == Some(*s),
            Self::StatusFaults(f) => m.status_faults == *f,
            Self::FaultReport(f) => m.fault_report == *f,
            Self::Feedback(k) => m.feedback == Some(*k),
        }
    }
}

/// A motor's observation from its last status frame and fault report.
pub(super) fn observe_motor(
    feedback: Option<Feedback>,
    report: Option<FaultReport>,
) -> MotorObservation {
    let mut m = MotorObservation::default();
    if let Some(f) = feedback {
        m.angle_rad = Some(f64::from(f.angle_rad));
        m.speed_rad_s = Some(f64::from(f.speed_rad_s));
        m.torque_nm = Some(f64::from(f.torque_nm));
        m.temperature_c = Some(f64::from(f.temperature_c));
        m.mode_state = Some(match f.mode {
            MotorMode::Reset => "reset",
            MotorMode::Calibration => "calibration",
            MotorMode::Run => "run",
            MotorMode::Brake => "brake",
        });
        m.status_faults = STATUS_FAULTS
            .iter()
            .enumerate()
            .filter(|(bit, _)| f.faults.0 & (1 << bit) != 0)
            .map(|(_, name)| *name)
            .collect();
        m.feedback = Some(match f.kind {
            FeedbackKind::Reply => "reply",
            FeedbackKind::ActiveReport => "active_report",
        });
    }
    if let Some(r) = report {
        let [a, b, c] = r.phase_over_current();
        let flags = [
            r.over_temperature(),
            r.gate_driver(),
            r.under_voltage(),
            r.over_voltage(),
            a,
            b,
            c,
            r.uncalibrated(),
            r.stall_overload(),
            r.over_temperature_warning(),
        ];
        m.fault_report = REPORT_FLAGS
            .iter()
            .zip(flags)
            .filter(|(_, on)| *on)
            .map(|(name, _)| *name)
            .collect();
    }
    m
}
