//! The trace columns of a Realman arm: joint angles, speeds, currents, temperatures, the pose,
//! and the arm state, errors and enable mask, from the driver's [`Observation`].

use super::model::ARM_STATES;
use super::observe::Observation;
use crate::devices::TraceColumn;
use crate::scenario::Signal;

/// Quanta of the trace (the snapshot stores integer multiples).
const DEG_Q: f64 = 0.1;
const A_Q: f64 = 0.01;
const C_Q: f64 = 1.0;
const MM_Q: f64 = 0.1;

/// The columns of one signal: (name, quantum, group).
fn signal_columns(signal: Signal, dof: usize) -> Vec<(String, f64, &'static str)> {
    let per_joint = |suffix: &str, q: f64, group: &'static str| {
        (1..=dof)
            .map(|j| (format!("j{j}_{suffix}"), q, group))
            .collect::<Vec<_>>()
    };
    match signal {
        Signal::Joints => per_joint("deg", DEG_Q, "angles"),
        Signal::Speeds => per_joint("deg_s", DEG_Q, "speeds"),
        Signal::Currents => per_joint("a", A_Q, "currents"),
        Signal::Temperatures => per_joint("c", C_Q, "temperatures"),
        Signal::Pose => ["x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"]
            .iter()
            .enumerate()
            .map(|(i, n)| ((*n).to_owned(), if i < 3 { MM_Q } else { DEG_Q }, "pose"))
            .collect(),
        Signal::Status => vec![
            ("arm_state".to_owned(), 1.0, "status"),
            ("error".to_owned(), 1.0, "status"),
            ("enabled_mask".to_owned(), 1.0, "status"),
        ],
        Signal::Gripper | Signal::Torques => Vec::new(),
    }
}

/// The trace columns for `signals`.
pub(super) fn columns(signals: &[Signal], dof: usize) -> Vec<TraceColumn> {
    signals
        .iter()
        .flat_map(|s| signal_columns(*s, dof))
        .map(|(name, quantum, group)| TraceColumn {
            name,
            quantum,
            group,
        })
        .collect()
}

/// One trace row matching [`columns`].
pub(super) fn row(signals: &[Signal], dof: usize, o: &Observation) -> Vec<Option<f64>> {
    let mut out = Vec::new();
    let joint = |v: &Option<Vec<f64>>, j: usize| v.as_ref().and_then(|v| v.get(j).copied());
    for signal in signals {
        match signal {
            Signal::Joints => out.extend((0..dof).map(|j| joint(&o.joints_deg, j))),
            Signal::Speeds => out.extend((0..dof).map(|j| joint(&o.speeds_deg_s, j))),
            Signal::Currents => out.extend((0..dof).map(|j| joint(&o.currents_a, j))),
            Signal::Temperatures => out.extend((0..dof).map(|j| joint(&o.temperatures_c, j))),
            Signal::Pose => {
                for i in 0..6 {
                    out.push(
                        o.pose
                            .map(|(p, e)| if i < 3 { p[i] * 1000.0 } else { e[i - 3] }),
                    );
                }
            }
            Signal::Status => {
                out.push(
                    o.arm_state
                        .and_then(|s| ARM_STATES.iter().position(|n| *n == s))
                        .map(|i| i as f64),
                );
                out.push(o.first_error.map(f64::from));
                out.push(o.enabled.as_ref().map(|e| {
                    e.iter()
                        .enumerate()
                        .filter(|(_, on)| **on)
                        .map(|(j, _)| f64::from(1u32 << j))
                        .sum()
                }));
            }
            Signal::Gripper | Signal::Torques => {}
        }
    }
    out
}
