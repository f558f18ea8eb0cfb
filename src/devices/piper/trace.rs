//! A Piper's trace columns: per joint angle, speed, current and temperature, the gripper, the
//! flange position, and the arm status with the enable mask.

use super::model::PIPER_JOINTS;
use super::observe::Observation;
use crate::devices::TraceColumn;
use crate::scenario::Signal;

/// Quantum of each signal group: coarse enough to be stable across harmless changes, fine
/// enough that a wrong scale factor (×10, ×1000, rad for deg) changes the snapshot.
const DEG_Q: f64 = 0.1;
const SPEED_Q: f64 = 0.1;
const AMP_Q: f64 = 0.01;
const MM_Q: f64 = 0.1;
const TEMP_Q: f64 = 1.0;

/// The columns for `signals`.
pub(super) fn columns(signals: &[Signal]) -> Vec<TraceColumn> {
    let mut cols = Vec::new();
    let mut push = |name: String, quantum: f64, group: &'static str| {
        cols.push(TraceColumn {
            name,
            quantum,
            group,
        });
    };
    for signal in signals {
        match signal {
            Signal::Joints => {
                (1..=PIPER_JOINTS).for_each(|j| push(format!("j{j}_deg"), DEG_Q, "joints"))
            }
            Signal::Speeds => {
                (1..=PIPER_JOINTS).for_each(|j| push(format!("v{j}_deg_s"), SPEED_Q, "speeds"))
            }
            Signal::Currents => {
                (1..=PIPER_JOINTS).for_each(|j| push(format!("i{j}_a"), AMP_Q, "currents"))
            }
            Signal::Gripper => push("gripper_mm".to_owned(), MM_Q, "gripper"),
            Signal::Pose => ["x", "y", "z"]
                .iter()
                .for_each(|a| push(format!("{a}_mm"), MM_Q, "pose")),
            Signal::Temperatures => {
                (1..=PIPER_JOINTS).for_each(|j| push(format!("t{j}_c"), TEMP_Q, "temperatures"))
            }
            Signal::Status => {
                push("arm_status".to_owned(), 1.0, "status");
                push("enabled_mask".to_owned(), 1.0, "status");
            }
            // The Piper reports motor current, not torque.
            Signal::Torques => {}
        }
    }
    cols
}

/// One row for `signals`, matching [`columns`].
pub(super) fn row(signals: &[Signal], obs: &Observation) -> Vec<Option<f64>> {
    let mut out = Vec::new();
    let per_joint = |values: &[f64], out: &mut Vec<Option<f64>>| {
        for j in 0..PIPER_JOINTS {
            out.push(values.get(j).copied());
        }
    };
    for signal in signals {
        match signal {
            Signal::Joints => per_joint(&obs.joints_deg, &mut out),
            Signal::Speeds => per_joint(&obs.speeds_deg_s, &mut out),
            Signal::Currents => per_joint(&obs.currents_a, &mut out),
            Signal::Gripper => out.push(obs.gripper_mm),
            Signal::Pose => {
                for i in 0..3 {
                    out.push(obs.position_mm.map(|p| p[i]));
                }
            }
            Signal::Temperatures => per_joint(&obs.motor_temps_c, &mut out),
            Signal::Status => {
                out.push(obs.arm_status_code.map(f64::from));
                let mask = (!obs.enabled.is_empty()).then(|| {
                    obs.enabled
                        .iter()
                        .enumerate()
                        .filter(|(_, e)| **e)
                        .map(|(i, _)| f64::from(1u32 << i))
                        .sum()
                });
                out.push(mask);
            }
            Signal::Torques => {}
        }
    }
    out
}
