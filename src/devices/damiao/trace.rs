//! A Damiao bus's trace columns: per motor (named by its ESC_ID) the position, velocity,
//! torque, the board and coil temperatures and the feedback's state nibble, for the recorded
//! signals.

use super::observe::MotorObservation;
use crate::devices::contract::motor_bus::{motor_columns, motor_row, MotorColumn};
use crate::devices::TraceColumn;
use crate::scenario::Signal;

/// Quanta: 1 mrad, 0.01 rad/s and 0.01 N·m resolve a wrong scale or sign in the snapshot (the
/// wire's own steps on a DM4310 are 0.4 mrad, 0.015 rad/s and 0.005 N·m).
const RAD_Q: f64 = 0.001;
const RAD_S_Q: f64 = 0.01;
const NM_Q: f64 = 0.01;
const TEMP_Q: f64 = 1.0;

/// The per-motor columns of one signal (empty for signals a Damiao motor has no value for).
fn signal_columns(signal: Signal) -> &'static [MotorColumn] {
    match signal {
        Signal::Joints => &[("rad", RAD_Q, "angles")],
        Signal::Speeds => &[("rad_s", RAD_S_Q, "speeds")],
        Signal::Torques => &[("nm", NM_Q, "torques")],
        Signal::Temperatures => &[
            ("mos_c", TEMP_Q, "temperatures"),
            ("rotor_c", TEMP_Q, "temperatures"),
        ],
        Signal::Status => &[("state", 1.0, "status")],
        Signal::Currents | Signal::Gripper | Signal::Pose => &[],
    }
}

/// The columns for `signals` and the motors `ids` (ESC_IDs, in bench order).
pub(super) fn columns(signals: &[Signal], ids: &[u16]) -> Vec<TraceColumn> {
    motor_columns(signals, ids, signal_columns)
}

/// One row, matching [`columns`]; `motors` in the same order as the ids given there.
pub(super) fn row(signals: &[Signal], motors: &[Option<&MotorObservation>]) -> Vec<Option<f64>> {
    motor_row(signals, motors, signal_columns, value)
}

fn value(suffix: &str, m: &MotorObservation) -> Option<f64> {
    match suffix {
        "rad" => m.position_rad,
        "rad_s" => m.velocity_rad_s,
        "nm" => m.torque_nm,
        "mos_c" => m.mos_temp_c,
        "rotor_c" => m.rotor_temp_c,
        "state" => m.state_code.map(f64::from),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_per_motor_and_rows_match_them() {
        let signals = [
            Signal::Joints,
            Signal::Temperatures,
            Signal::Status,
            Signal::Gripper,
        ];
        let cols = columns(&signals, &[1, 3]);
        let names: Vec<&str> = cols.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "m1_rad",
                "m3_rad",
                "m1_mos_c",
                "m3_mos_c",
                "m1_rotor_c",
                "m3_rotor_c",
                "m1_state",
                "m3_state"
            ]
        );
        let m = MotorObservation {
            position_rad: Some(0.5),
            mos_temp_c: Some(30.0),
            rotor_temp_c: Some(41.0),
            state_code: Some(0xD),
            state: Some("communication_lost"),
            ..MotorObservation::default()
        };
        let row = row(&signals, &[Some(&m), None]);
        assert_eq!(row.len(), cols.len());
        assert_eq!(
            row,
            [
                Some(0.5),
                None,
                Some(30.0),
                None,
                Some(41.0),
                None,
                Some(13.0),
                None
            ]
        );
    }
}
