//! Real-time bookkeeping shared by the emulators' transmit and clock tasks: frames per ID,
//! inter-frame period percentiles per ID, the clock task's wake-up periods, late wake-ups and
//! overruns.
//!
//! Periods go into a fixed histogram (10 µs bins up to 100 ms) so a long run costs constant
//! memory; percentiles are therefore accurate to one bin (reported at its lower edge).

use std::collections::BTreeMap;
use std::fmt;
use std::time::Duration;

use tokio::time::Instant;

/// Histogram bin width, µs.
const BIN_US: u64 = 10;
/// Number of bins (10 µs × 10 000 = 100 ms); longer periods land in the last bin.
const BINS: usize = 10_000;

#[derive(Debug, Clone)]
struct IdRecord {
    frames: u64,
    last: Instant,
    bins: Vec<u32>,
    max: Duration,
}

impl IdRecord {
    fn starting_at(at: Instant) -> Self {
        Self {
            frames: 1,
            last: at,
            bins: vec![0; BINS],
            max: Duration::ZERO,
        }
    }

    /// One more event at `at`: the period since the previous one goes into the histogram.
    fn record(&mut self, at: Instant) {
        let period = at.saturating_duration_since(self.last);
        let bin = (period.as_micros() as u64 / BIN_US).min(BINS as u64 - 1) as usize;
        self.bins[bin] = self.bins[bin].saturating_add(1);
        self.max = self.max.max(period);
        self.frames += 1;
        self.last = at;
    }

    fn percentile(&self, q: f64) -> Option<Duration> {
        let total: u64 = self.bins.iter().map(|&c| u64::from(c)).sum();
        if total == 0 {
            return None;
        }
        // Rank of the q-quantile among `total` samples (1-based, nearest rank).
        let rank = ((q * total as f64).ceil() as u64).clamp(1, total);
        let mut seen = 0u64;
        for (i, &c) in self.bins.iter().enumerate() {
            seen += u64::from(c);
            if seen >= rank {
                // The bin's lower edge: the true value is at most one bin above.
                return Some(Duration::from_micros(i as u64 * BIN_US));
            }
        }
        Some(self.max)
    }
}

/// Counters a running emulator keeps about its own timing.
#[derive(Debug, Clone)]
pub(crate) struct RealtimeCounters {
    started: Instant,
    ids: BTreeMap<u32, IdRecord>,
    /// The clock task's wake-ups, as periods between them.
    wakes: Option<IdRecord>,
    steps: u64,
    late_wakeups: u64,
    overruns: u64,
    skipped_steps: u64,
}

impl RealtimeCounters {
    /// Counters starting now.
    pub(crate) fn new() -> Self {
        Self {
            started: Instant::now(),
            ids: BTreeMap::new(),
            wakes: None,
            steps: 0,
            late_wakeups: 0,
            overruns: 0,
            skipped_steps: 0,
        }
    }

    /// A frame with `id` left on the bus at `at`.
    pub(crate) fn record_frame(&mut self, id: u32, at: Instant) {
        match self.ids.get_mut(&id) {
            Some(r) => r.record(at),
            None => {
                self.ids.insert(id, IdRecord::starting_at(at));
            }
        }
    }

    /// A wake-up of the clock task at `at` ran `steps` steps; `late` when it had to catch up.
    pub(crate) fn record_wakeup(&mut self, at: Instant, steps: u64, late: bool) {
        match &mut self.wakes {
            Some(w) => w.record(at),
            None => self.wakes = Some(IdRecord::starting_at(at)),
        }
        self.steps += steps;
        if late {
            self.late_wakeups += 1;
        }
    }

    /// The clock fell further behind than it may catch up and dropped `skipped` steps.
    pub(crate) fn record_overrun(&mut self, skipped: u64) {
        self.overruns += 1;
        self.skipped_steps += skipped;
    }

    /// A copy for the caller.
    pub(crate) fn report(&self) -> RealtimeStats {
        let elapsed = self.started.elapsed();
        let secs = elapsed.as_secs_f64().max(1e-9);
        RealtimeStats {
            elapsed,
            steps: self.steps,
            late_wakeups: self.late_wakeups,
            overruns: self.overruns,
            skipped_steps: self.skipped_steps,
            wake_period_p50: self.wakes.as_ref().and_then(|w| w.percentile(0.50)),
            wake_period_p99: self.wakes.as_ref().and_then(|w| w.percentile(0.99)),
            wake_period_max: self
                .wakes
                .as_ref()
                .and_then(|w| (w.frames > 1).then_some(w.max)),
            ids: self
                .ids
                .iter()
                .map(|(&id, r)| IdStats {
                    id,
                    frames: r.frames,
                    rate_hz: r.frames as f64 / secs,
                    period_p50: r.percentile(0.50),
                    period_p99: r.percentile(0.99),
                    period_max: (r.frames > 1).then_some(r.max),
                })
                .collect(),
        }
    }
}

/// Timing of one CAN ID the emulator sent.
#[derive(Debug, Clone, PartialEq)]
pub struct IdStats {
    /// The raw CAN ID.
    pub id: u32,
    /// Frames sent.
    pub frames: u64,
    /// Frames per second over the emulator's lifetime.
    pub rate_hz: f64,
    /// Median time between two frames of this ID (`None` with fewer than two frames).
    pub period_p50: Option<Duration>,
    /// 99th percentile of the time between two frames.
    pub period_p99: Option<Duration>,
    /// Longest time between two frames.
    pub period_max: Option<Duration>,
}

/// What an emulator measured about its own real-time behaviour.
#[derive(Debug, Clone, PartialEq)]
pub struct RealtimeStats {
    /// Time since the emulator started.
    pub elapsed: Duration,
    /// Control steps run.
    pub steps: u64,
    /// Wake-ups that found the clock behind and ran the missed steps.
    pub late_wakeups: u64,
    /// Times the backlog exceeded the catch-up bound and steps were dropped.
    pub overruns: u64,
    /// Steps dropped by overruns (each one is a step of emulated time lost).
    pub skipped_steps: u64,
    /// Median time between two wake-ups of the clock task (`None` before the second).
    pub wake_period_p50: Option<Duration>,
    /// 99th percentile of the time between two wake-ups: its excess over the nominal
    /// period is how late the clock runs at worst, short of the rare stalls.
    pub wake_period_p99: Option<Duration>,
    /// Longest time between two wake-ups.
    pub wake_period_max: Option<Duration>,
    /// Per-ID figures, by ID.
    pub ids: Vec<IdStats>,
}

impl RealtimeStats {
    /// Figures of one ID.
    pub fn id(&self, id: u32) -> Option<&IdStats> {
        self.ids.iter().find(|s| s.id == id)
    }
}

fn ms(d: Option<Duration>) -> String {
    d.map_or_else(
        || "-".to_string(),
        |d| format!("{:.3}", d.as_secs_f64() * 1e3),
    )
}

impl fmt::Display for RealtimeStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:.1} s, {} steps, {} late wake-ups, {} overruns ({} steps dropped)",
            self.elapsed.as_secs_f64(),
            self.steps,
            self.late_wakeups,
            self.overruns,
            self.skipped_steps
        )?;
        writeln!(
            f,
            "wake-up period p50 {} ms, p99 {} ms, max {} ms",
            ms(self.wake_period_p50),
            ms(self.wake_period_p99),
            ms(self.wake_period_max)
        )?;
        writeln!(
            f,
            "{:>6} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "id", "frames", "Hz", "p50 ms", "p99 ms", "max ms"
        )?;
        for s in &self.ids {
            writeln!(
                f,
                "{:>#6x} {:>9} {:>9.1} {:>9} {:>9} {:>9}",
                s.id,
                s.frames,
                s.rate_hz,
                ms(s.period_p50),
                ms(s.period_p99),
                ms(s.period_max)
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_follow_the_recorded_periods() {
        let mut c = RealtimeCounters::new();
        let t0 = Instant::now();
        // 99 periods of 5 ms and one of 40 ms.
        let mut t = t0;
        c.record_frame(0x2A1, t);
        for i in 0..100 {
            t += Duration::from_millis(if i == 50 { 40 } else { 5 });
            c.record_frame(0x2A1, t);
        }
        let r = c.report();
        let s = r.id(0x2A1).expect("recorded");
        assert_eq!(s.frames, 101);
        assert_eq!(s.period_p50, Some(Duration::from_millis(5)));
        assert_eq!(s.period_p99, Some(Duration::from_millis(5)));
        assert_eq!(s.period_max, Some(Duration::from_millis(40)));
        c.record_overrun(120);
        c.record_wakeup(t0, 5, true);
        c.record_wakeup(t0 + Duration::from_micros(1_130), 1, false);
        let r = c.report();
        assert_eq!(
            (r.overruns, r.skipped_steps, r.late_wakeups, r.steps),
            (1, 120, 1, 6)
        );
        // One wake-up period, 1.13 ms: reported at its 10 µs bin's lower edge.
        assert_eq!(r.wake_period_p99, Some(Duration::from_micros(1_130)));
        assert_eq!(r.wake_period_max, Some(Duration::from_micros(1_130)));
        assert!(r.to_string().contains("0x2a1"));
    }
}
