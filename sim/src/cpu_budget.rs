//! How much catching up a late wake-up of a real-time emulator may do, bounded by the CPU it
//! would take.
//!
//! A late wake-up runs the steps it missed so emulated time keeps up with the wall clock. On
//! a machine fast enough for real time that is a short burst. On one too slow (an emulated
//! VM, where one physics step can cost more than the millisecond it emulates) catching up can
//! never succeed: every wake-up would run a full backlog, take the CPU from the clients the
//! emulator serves and fall further behind. The budget measures what a step costs and lets a
//! wake-up run only as many steps as fit in a share of the wall time since the last wake-up;
//! the rest is dropped and counted as an overrun, so the emulator falls behind gracefully.

use std::time::Duration;

/// Default share of one core a catch-up may use: half, leaving the other half (on a
/// two-core machine, a whole core besides) to the clients and the bus.
pub const DEFAULT_CPU_SHARE: f64 = 0.5;

/// Weight of the newest measurement in the running step cost (an exponential average over
/// roughly the last 20 wake-ups, so one slow wake-up does not swing the limit).
const COST_WEIGHT: f64 = 0.05;

/// The running estimate of a step's cost and the share of CPU a catch-up may take.
#[derive(Debug, Clone)]
pub struct CpuBudget {
    share: f64,
    step_cost_s: Option<f64>,
}

impl CpuBudget {
    /// A budget of `share` (0–1] of one core; values outside fall back to
    /// [`DEFAULT_CPU_SHARE`].
    pub fn new(share: f64) -> Self {
        let share = if share.is_finite() && share > 0.0 && share <= 1.0 {
            share
        } else {
            DEFAULT_CPU_SHARE
        };
        Self {
            share,
            step_cost_s: None,
        }
    }

    /// The measured cost of one step, once a wake-up has been measured.
    pub fn step_cost(&self) -> Option<Duration> {
        self.step_cost_s.map(Duration::from_secs_f64)
    }

    /// Record that `steps` steps took `took` of wall time.
    pub fn observe(&mut self, steps: u64, took: Duration) {
        if steps == 0 {
            return;
        }
        let cost = took.as_secs_f64() / steps as f64;
        self.step_cost_s = Some(match self.step_cost_s {
            None => cost,
            Some(old) => old + COST_WEIGHT * (cost - old),
        });
    }

    /// Most steps a wake-up may run after `since_last` of wall time since the previous one:
    /// what fits in the share of that time at the measured cost, never fewer than `floor`
    /// (one wake's worth, so emulated time always advances) nor more than `ceiling` (the
    /// configured catch-up limit). Before any measurement, `ceiling`.
    pub fn limit(&self, since_last: Duration, floor: u64, ceiling: u64) -> u64 {
        let ceiling = ceiling.max(floor);
        let Some(cost) = self.step_cost_s.filter(|c| *c > 0.0) else {
            return ceiling;
        };
        let affordable = (self.share * since_last.as_secs_f64() / cost).floor();
        // `as` saturates: an absurdly cheap step gives u64::MAX, then the ceiling applies.
        (affordable as u64).clamp(floor, ceiling)
    }
}

impl Default for CpuBudget {
    fn default() -> Self {
        Self::new(DEFAULT_CPU_SHARE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn before_any_measurement_the_configured_limit_applies() {
        assert_eq!(CpuBudget::default().limit(50 * MS, 5, 100), 100);
    }

    #[test]
    fn a_fast_machine_catches_up_the_whole_backlog() {
        let mut budget = CpuBudget::default();
        budget.observe(5, Duration::from_micros(250)); // 50 µs a step.
                                                       // 20 ms late: 20 steps cost 1 ms, well inside half of 20 ms.
        assert!(budget.limit(20 * MS, 5, 100) >= 20);
        assert_eq!(budget.limit(40 * MS, 5, 100), 100, "capped by the ceiling");
    }

    #[test]
    fn a_machine_too_slow_for_real_time_runs_one_wake_per_wake() {
        let mut budget = CpuBudget::default();
        budget.observe(5, 10 * MS); // 2 ms a step: real time is impossible.
                                    // 5 ms since the last wake: half of it buys one step, the floor gives five.
        assert_eq!(budget.limit(5 * MS, 5, 100), 5);
        // After a 100 ms stall: 50 ms of CPU buys 25 steps, not the 100 of the backlog.
        assert_eq!(budget.limit(100 * MS, 5, 100), 25);
    }

    #[test]
    fn the_cost_is_a_running_average() {
        let mut budget = CpuBudget::default();
        budget.observe(1, MS);
        budget.observe(1, 101 * MS);
        let cost = budget.step_cost().unwrap().as_secs_f64();
        assert!((cost - 0.006).abs() < 1e-9, "{cost}");
        budget.observe(0, Duration::from_secs(10));
        assert_eq!(
            budget.step_cost().unwrap().as_secs_f64(),
            cost,
            "0 steps ignored"
        );
    }

    #[test]
    fn nonsense_shares_fall_back_to_the_default() {
        for share in [0.0, -1.0, 2.0, f64::NAN] {
            let mut budget = CpuBudget::new(share);
            budget.observe(1, MS);
            assert_eq!(budget.limit(10 * MS, 1, 100), 5, "share {share}");
        }
    }
}
