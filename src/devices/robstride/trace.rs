//! A RobStride bus's trace columns: per motor (named by its power-on CAN ID) the angle, speed,
//! torque, temperature, mode state and status-frame fault bits, for the recorded signals.

use super::model::{MODE_STATES, STATUS_FAULTS};
use super::observe::MotorObservation;
use crate::devices::contract::motor_bus::{motor_columns, motor_row, MotorColumn};
use crate::devices::TraceColumn;
use crate::scenario::Signal;

/// Quanta: 1 mrad, 0.01 rad/s and 0.01 N·m resolve a wrong scale or sign in the snapshot.
const RAD_Q: f64 = 0.001;
const RAD_S_Q: f64 = 0.01;
const NM_Q: f64 = 0.01;
const TEMP_Q: f64 = 1.0;

/// The per-motor columns of one signal (empty for signals a RobStride has no value for).
fn signal_columns(signal: Signal) -> &'static [MotorColumn] {
    match signal {
        Signal::Joints => &[("rad", RAD_Q, "angles")],
        Signal::Speeds => &[("rad_s", RAD_S_Q, "speeds")],
        Signal::Torques => &[("nm", NM_Q, "torques")],
        Signal::Temperatures => &[("c", TEMP_Q, "temperatures")],
        Signal::Status => &[("mode", 1.0, "status"), ("faults", 1.0, "status")],
        Signal::Currents | Signal::Gripper | Signal::Pose => &[],
    }
}

/// The columns for `signals` and the motors `ids` (power-on CAN IDs, in bench order).
pub(super) fn columns(signals: &[Signal], ids: &[u8]) -> Vec<TraceColumn> {
    motor_columns(signals, ids, signal_columns)
}

/// The status-frame fault bits as a number (bit `i` = [`STATUS_FAULTS`]`[i]`).
fn fault_bits(m: &MotorObservation) -> f64 {
    STATUS_FAULTS
        .iter()
        .enumerate()
        .filter(|(_, name)| m.status_faults.contains(name))
        .map(|(bit, _)| f64::from(1u32 << bit))
        .sum()
}

/// One row, matching [`columns`]; `motors` in the same order as the ids given there.
pub(super) fn row(signals: &[Signal], motors: &[Option<&MotorObservation>]) -> Vec<Option<f64>> {
    motor_row(signals, motors, signal_columns, value)
}

fn value(suffix: &str, m: &MotorObservation) -> Option<f64> {
    match suffix {
        "rad" => m.angle_rad,
        "rad_s" => m.speed_rad_s,
        "nm" => m.torque_nm,
        "c" => m.temperature_c,
        "mode" => m
            .mode_state
            .and_then(|s| MODE_STATES.iter().position(|n| *n == s))
            .map(|i| i as f64),
        // Known once a status frame came.
        "faults" => m.mode_state.map(|_| fault_bits(m)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_per_motor_and_rows_match_them() {
        let signals = [Signal::Joints, Signal::Status, Signal::Gripper];
        let cols = columns(&signals, &[1, 2]);
        let names: Vec<&str> = cols.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "m1_rad",
                "m2_rad",
                "m1_mode",
                "m2_mode",
                "m1_faults",
                "m2_faults"
            ]
        );
        let m = MotorObservation {
            angle_rad: Some(0.5),
            mode_state: Some("run"),
            status_faults: vec!["over_temperature"],
            ..MotorObservation::default()
        };
        let row = row(&signals, &[Some(&m), None]);
        assert_eq!(row.len(), cols.len());
        let bit = STATUS_FAULTS
            .iter()
            .position(|n| *n == "over_temperature")
            .expect("a status fault");
        assert_eq!(
            row,
            [
                Some(0.5),
                None,
                Some(2.0),
                None,
                Some(f64::from(1u32 << bit)),
                None
            ]
        );
    }
}
