//! Damiao motors as the driver sees them: the last feedback frame of each motor (the reply to
//! a command, a refresh or the host's periodic read), and the per-motor conditions judged
//! against it.

use std::collections::BTreeMap;

use driver::damiao::Feedback;

use super::model::{state_name, MotorCond};
use crate::devices::contract::motor_bus::fixed;
use crate::scenario::Near;

/// Every motor of the bus by ESC_ID.
pub type Observation = BTreeMap<u16, MotorObservation>;

/// One motor as the driver last saw it (every field `None` before its first feedback).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MotorObservation {
    /// Position (rad).
    pub position_rad: Option<f64>,
    /// Velocity (rad/s).
    pub velocity_rad_s: Option<f64>,
    /// Torque (N·m).
    pub torque_nm: Option<f64>,
    /// The state nibble.
    pub state_code: Option<u8>,
    /// Its name ([`STATES`](super::model::STATES), `unknown` for an undocumented nibble).
    pub state: Option<&'static str>,
    /// Driver board (MOS) temperature (°C).
    pub mos_temp_c: Option<f64>,
    /// Coil (rotor) temperature (°C).
    pub rotor_temp_c: Option<f64>,
}

impl MotorObservation {
    /// A motor's observation from its last feedback frame.
    pub fn of(feedback: Option<Feedback>) -> Self {
        let Some(f) = feedback else {
            return Self::default();
        };
        Self {
            position_rad: Some(f64::from(f.position_rad)),
            velocity_rad_s: Some(f64::from(f.velocity_rad_s)),
            torque_nm: Some(f64::from(f.torque_nm)),
            state_code: Some(f.state.code()),
            state: Some(state_name(f.state)),
            mos_temp_c: Some(f64::from(f.mos_temp_c)),
            rotor_temp_c: Some(f64::from(f.rotor_temp_c)),
        }
    }
}

pub(super) fn near_text(n: &Near) -> String {
    format!("{} ± {}", fixed(n.value, 3), fixed(n.tolerance, 3))
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "unknown".to_owned(), |v| fixed(v, 3))
}

impl MotorCond {
    /// What the condition wants, for reports.
    pub fn expected_text(&self, motor: u16) -> String {
        let what = match self {
            Self::Position(n) => format!("position_rad {}", near_text(n)),
            Self::Velocity(n) => format!("velocity_rad_s {}", near_text(n)),
            Self::Torque(n) => format!("torque_nm {}", near_text(n)),
            Self::State(s) => format!("state {s}"),
            Self::MosTemp(n) => format!("mos_temp_c {}", near_text(n)),
            Self::RotorTemp(n) => format!("rotor_temp_c {}", near_text(n)),
        };
        format!("motor {motor} {what}")
    }

    /// What the motor shows for this condition, for reports.
    pub fn actual_text(&self, motor: u16, obs: &Observation) -> String {
        let Some(m) = obs.get(&motor) else {
            return format!("motor {motor} not on the bus");
        };
        let what = match self {
            Self::Position(_) => format!("position_rad {}", opt(m.position_rad)),
            Self::Velocity(_) => format!("velocity_rad_s {}", opt(m.velocity_rad_s)),
            Self::Torque(_) => format!("torque_nm {}", opt(m.torque_nm)),
            Self::State(_) => format!("state {}", m.state.unwrap_or("unknown (no feedback yet)")),
            Self::MosTemp(_) => format!("mos_temp_c {}", opt(m.mos_temp_c)),
            Self::RotorTemp(_) => format!("rotor_temp_c {}", opt(m.rotor_temp_c)),
        };
        format!("motor {motor} {what}")
    }

    /// Whether the condition holds.
    pub fn holds(&self, motor: u16, obs: &Observation) -> bool {
        let Some(m) = obs.get(&motor) else {
            return false;
        };
        let near =
            |v: Option<f64>, n: &Near| v.is_some_and(|v| (v - n.value).abs() <= n.tolerance + 1e-9);
        match self {
            Self::Position(n) => near(m.position_rad, n),
            Self::Velocity(n) => near(m.velocity_rad_s, n),
            Self::Torque(n) => near(m.torque_nm, n),
            Self::State(s) => m.state == Some(*s),
            Self::MosTemp(n) => near(m.mos_temp_c, n),
            Self::RotorTemp(n) => near(m.rotor_temp_c, n),
        }
    }
}

#[cfg(test)]
mod tests {
    use driver::damiao::MotorState;

    use super::*;

    fn feedback(state: MotorState) -> Feedback {
        Feedback {
            motor: 1,
            state,
            position_rad: 0.5,
            velocity_rad_s: -1.25,
            torque_nm: 2.0,
            mos_temp_c: 31,
            rotor_temp_c: 40,
        }
    }

    #[test]
    fn conditions_judge_the_right_motor_and_name_what_it_shows() {
        let mut obs = Observation::new();
        obs.insert(1, MotorObservation::of(Some(feedback(MotorState::Enabled))));
        obs.insert(2, MotorObservation::of(None));
        let near = |value, tolerance| Near { value, tolerance };
        assert!(MotorCond::Position(near(0.45, 0.05)).holds(1, &obs));
        assert!(!MotorCond::Position(near(0.4, 0.05)).holds(1, &obs));
        assert!(MotorCond::Velocity(near(-1.25, 0.0)).holds(1, &obs));
        assert!(MotorCond::State("enabled").holds(1, &obs));
        assert!(!MotorCond::State("enabled").holds(2, &obs));
        assert!(!MotorCond::State("enabled").holds(3, &obs));
        assert!(MotorCond::RotorTemp(near(41.0, 1.0)).holds(1, &obs));
        assert!(!MotorCond::MosTemp(near(41.0, 1.0)).holds(1, &obs));
        assert_eq!(
            MotorCond::State("enabled").actual_text(2, &obs),
            "motor 2 state unknown (no feedback yet)"
        );
        assert_eq!(
            MotorCond::Torque(near(0.0, 0.5)).actual_text(1, &obs),
            "motor 1 torque_nm 2.000"
        );
        assert_eq!(
            MotorCond::Torque(near(-0.0, 0.5)).expected_text(1),
            "motor 1 torque_nm 0.000 ± 0.500"
        );
        let lost = MotorObservation::of(Some(feedback(MotorState::CommunicationLost)));
        assert_eq!(
            (lost.state, lost.state_code),
            (Some("communication_lost"), Some(0xD))
        );
    }
}
