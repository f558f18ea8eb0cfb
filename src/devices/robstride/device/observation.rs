//! Every motor as the driver last saw it, through the protocol it last spoke.

use driver::robstride::{MitStatus, MotorMode};

use super::{lock, RobstrideDevice};
use crate::devices::robstride::observe::{observe_motor, MotorObservation, Observation};

/// A motor seen through its last MIT Response 1. The variant has no status fault bits and no
/// type-21 report (only a fault flag), so `faults` and `fault_report` read empty; every frame
/// is a reply.
fn observe_mit(s: &MitStatus) -> MotorObservation {
    MotorObservation {
        angle_rad: Some(f64::from(s.angle_rad)),
        speed_rad_s: Some(f64::from(s.speed_rad_s)),
        torque_nm: Some(f64::from(s.torque_nm)),
        temperature_c: Some(f64::from(s.temperature_c)),
        mode_state: Some(match s.mode {
            MotorMode::Reset => "reset",
            MotorMode::Calibration => "calibration",
            MotorMode::Run => "run",
            MotorMode::Brake => "brake",
        }),
        status_faults: Vec::new(),
        fault_report: Vec::new(),
        feedback: Some("reply"),
    }
}

impl RobstrideDevice {
    /// Every motor as the driver last saw it (through the protocol it last spoke).
    pub(super) fn observe(&self) -> Observation {
        let mit_active = lock(&self.mit_active).clone();
        let mit = lock(&self.mit_motors);
        lock(&self.motors)
            .iter()
            .map(|(id, motor)| {
                let via_mit = mit_active
                    .contains(id)
                    .then(|| mit.get(id).and_then(|m| m.last_status()))
                    .flatten();
                let seen = match via_mit {
                    Some(status) => observe_mit(&status),
                    None => observe_motor(motor.last_feedback(), motor.last_fault_report()),
                };
                (*id, seen)
            })
            .collect()
    }
}
