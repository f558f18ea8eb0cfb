//! Sampling device state into a quantised trace.

use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use tokio::time::{Instant, MissedTickBehavior};

use crate::harness::device::{Device, Observation};
use crate::harness::model::{Record, Signal, PIPER_JOINTS};
use crate::harness::result::{Column, Trace};

/// Quantum of each signal group: coarse enough to be stable across harmless changes, fine
/// enough that a wrong scale factor (×10, ×1000, rad for deg) changes the snapshot.
const DEG_Q: f64 = 0.1;
const SPEED_Q: f64 = 0.1;
const AMP_Q: f64 = 0.01;
const MM_Q: f64 = 0.1;
const TEMP_Q: f64 = 1.0;

fn columns(record: &Record, devices: &[Arc<dyn Device>]) -> Vec<Column> {
    let mut cols = Vec::new();
    for dev in devices {
        let prefix = if devices.len() > 1 {
            format!("{}.", dev.name())
        } else {
            String::new()
        };
        let mut push = |name: String, quantum: f64, group: &'static str| {
            cols.push(Column {
                name: format!("{prefix}{name}"),
                quantum,
                group,
            });
        };
        for signal in &record.signals {
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
            }
        }
    }
    cols
}

fn quantise(value: Option<f64>, quantum: f64) -> Option<i64> {
    value.filter(|v| v.is_finite()).map(|v| {
        let q = (v / quantum).round();
        // Avoid "-0": a value that rounds to zero is zero.
        if q == 0.0 {
            0
        } else {
            q as i64
        }
    })
}

fn row(record: &Record, obs: &Observation) -> Vec<Option<i64>> {
    let mut out = Vec::new();
    let per_joint = |values: &[f64], q: f64, out: &mut Vec<Option<i64>>| {
        for j in 0..PIPER_JOINTS {
            out.push(quantise(values.get(j).copied(), q));
        }
    };
    for signal in &record.signals {
        match signal {
            Signal::Joints => per_joint(&obs.joints_deg, DEG_Q, &mut out),
            Signal::Speeds => per_joint(&obs.speeds_deg_s, SPEED_Q, &mut out),
            Signal::Currents => per_joint(&obs.currents_a, AMP_Q, &mut out),
            Signal::Gripper => out.push(quantise(obs.gripper_mm, MM_Q)),
            Signal::Pose => {
                for i in 0..3 {
                    out.push(quantise(obs.position_mm.map(|p| p[i]), MM_Q));
                }
            }
            Signal::Temperatures => per_joint(&obs.motor_temps_c, TEMP_Q, &mut out),
            Signal::Status => {
                out.push(obs.arm_status_code.map(i64::from));
                let mask = if obs.enabled.is_empty() {
                    None
                } else {
                    Some(
                        obs.enabled
                            .iter()
                            .enumerate()
                            .filter(|(_, e)| **e)
                            .map(|(i, _)| 1i64 << i)
                            .sum(),
                    )
                };
                out.push(mask);
            }
        }
    }
    out
}

/// A running sampler; [`Sampler::finish`] returns the trace.
pub(crate) struct Sampler {
    trace: Arc<Mutex<Trace>>,
    task: tokio::task::JoinHandle<()>,
}

impl Sampler {
    /// Start sampling every `record.sample_period` from `t0` (first sample immediately).
    pub fn start(record: &Record, devices: Vec<Arc<dyn Device>>, t0: Instant) -> Self {
        let trace = Arc::new(Mutex::new(Trace {
            period: record.sample_period,
            columns: columns(record, &devices),
            rows: Vec::new(),
        }));
        let shared = Arc::clone(&trace);
        let record = record.clone();
        let task = tokio::spawn(async move {
            let mut ticker = tokio::time::interval_at(t0, record.sample_period);
            ticker.set_missed_tick_behavior(MissedTickBehavior::Skip);
            loop {
                ticker.tick().await;
                let at = t0.elapsed();
                let mut values = Vec::new();
                for dev in &devices {
                    values.extend(row(&record, &dev.observe()));
                }
                let at = round_to_period(at, record.sample_period);
                shared
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .rows
                    .push((at, values));
            }
        });
        Self { trace, task }
    }

    /// Stop sampling and return the trace.
    pub fn finish(self) -> Trace {
        self.task.abort();
        let trace = self.trace.lock().unwrap_or_else(PoisonError::into_inner);
        trace.clone()
    }
}

/// In real time ticks land a little late; report the nominal tick time.
fn round_to_period(at: Duration, period: Duration) -> Duration {
    let p = period.as_nanos().max(1);
    let n = (at.as_nanos() + p / 2) / p;
    Duration::from_nanos(u64::try_from(n * p).unwrap_or(u64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantise_rounds_to_the_quantum_and_has_no_negative_zero() {
        assert_eq!(quantise(Some(90.04), 0.1), Some(900));
        assert_eq!(quantise(Some(-0.04), 0.1), Some(0));
        assert_eq!(quantise(Some(1.234), 0.01), Some(123));
        assert_eq!(quantise(None, 0.1), None);
        assert_eq!(quantise(Some(f64::NAN), 0.1), None);
    }

    #[test]
    fn late_real_time_ticks_report_the_nominal_time() {
        let p = Duration::from_millis(50);
        assert_eq!(
            round_to_period(Duration::from_micros(100_300), p),
            Duration::from_millis(100)
        );
    }
}
