//! Sampling device state into a quantised trace.

use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use tokio::time::{Instant, MissedTickBehavior};

use crate::devices::Device;
use crate::harness::model::{Record, Signal};
use crate::harness::result::{Column, Trace};

/// Every device's columns, prefixed with the device name on multi-device benches.
fn columns(signals: &[Signal], devices: &[Arc<dyn Device>]) -> Vec<Column> {
    let mut cols = Vec::new();
    for dev in devices {
        let prefix = if devices.len() > 1 {
            format!("{}.", dev.name())
        } else {
            String::new()
        };
        for c in dev.trace_columns(signals) {
            cols.push(Column {
                name: format!("{prefix}{}", c.name),
                quantum: c.quantum,
                group: c.group,
            });
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

/// Most rows a trace keeps. An hour at the default 50 ms period would be 72,000 rows in the
/// snapshot, the plot and the report; past this many the sampler halves its rate instead
/// (see [`thin_out`]), so every run's trace stays a few megabytes at most.
pub(crate) const MAX_TRACE_ROWS: usize = 20_000;

/// Halve a full trace: keep the rows at multiples of twice the period (the first row is at
/// time zero) and double the period, which later samples then follow.
fn thin_out(trace: &mut Trace) {
    let period = trace.period * 2;
    trace.rows.retain(|(at, _)| on_period(*at, period));
    trace.period = period;
}

/// Whether `at` falls on a multiple of `period`.
fn on_period(at: Duration, period: Duration) -> bool {
    at.as_nanos().is_multiple_of(period.as_nanos().max(1))
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
            columns: columns(&record.signals, &devices),
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
                    let quanta = dev.trace_columns(&record.signals);
                    let row = dev.trace_row(&record.signals);
                    values.extend(
                        quanta
                            .iter()
                            .enumerate()
                            .map(|(i, c)| quantise(row.get(i).copied().flatten(), c.quantum)),
                    );
                }
                let at = round_to_period(at, record.sample_period);
                let mut trace = shared.lock().unwrap_or_else(PoisonError::into_inner);
                // After thinning out, only the ticks on the longer period are kept.
                if on_period(at, trace.period) {
                    trace.rows.push((at, values));
                    if trace.rows.len() >= MAX_TRACE_ROWS {
                        thin_out(&mut trace);
                    }
                }
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
    fn a_full_trace_keeps_every_other_row_at_twice_the_period() {
        let period = Duration::from_millis(50);
        let mut trace = Trace {
            period,
            columns: Vec::new(),
            rows: (0..MAX_TRACE_ROWS as u32)
                .map(|i| (period * i, vec![Some(i64::from(i))]))
                .collect(),
        };
        thin_out(&mut trace);
        assert_eq!(trace.period, Duration::from_millis(100));
        assert_eq!(trace.rows.len(), MAX_TRACE_ROWS / 2);
        assert_eq!(trace.rows[1], (Duration::from_millis(100), vec![Some(2)]));
        assert!(on_period(Duration::from_millis(1_000_100), trace.period));
        assert!(!on_period(Duration::from_millis(1_000_050), trace.period));
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
