//! Options of a run beyond its clock: deadline scaling, interruption, recording limits.

use std::time::Duration;

use super::Interrupt;

/// Options of a run beyond the clock.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Multiplies every deadline (`wait_until` and action `timeout_ms`, the driver's own
    /// timeouts) for real-time runs on slow machines (e.g. a vcan VM under emulation). Waits
    /// (`wait_ms`) and hold durations (`for_ms`) are not scaled. 1 in virtual time.
    pub time_scale: f64,
    /// Added to every deadline after scaling: room for the stalls of a slow machine (a VM
    /// under emulation pauses a process for seconds now and then), which a factor alone would
    /// give short deadlines too little of and long ones far too much. Zero in virtual time.
    pub deadline_slack: Duration,
    /// Fired to stop the run early (SIGINT, SIGTERM): the step running ends at once, the
    /// rest are not run, and the outputs are still written.
    pub interrupt: Interrupt,
    /// The size limit of each bus recording file (`bus.log`, `bus.pcap`); past it a recording
    /// keeps the run's beginning and end (see `crate::harness::report` and
    /// `crate::harness::Omitted`).
    pub recording_limit_bytes: u64,
}

/// Default size limit of each bus recording file: 64 MiB holds ~7 minutes of a Piper's
/// traffic (~3,000 frames/s), the first half and the last of a longer run.
pub const DEFAULT_RECORDING_LIMIT_BYTES: u64 = 64 << 20;

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            time_scale: 1.0,
            deadline_slack: Duration::ZERO,
            interrupt: Interrupt::default(),
            recording_limit_bytes: DEFAULT_RECORDING_LIMIT_BYTES,
        }
    }
}

impl RunOptions {
    /// Scale a deadline and add the slack. Never panics: a factor that would overflow
    /// `Duration` (`Duration::mul_f64` panics there) gives [`MAX_DEADLINE`], and so does
    /// anything longer; the CLI refuses such factors before a run starts.
    pub(crate) fn deadline(&self, d: Duration) -> Duration {
        let scaled = if self.time_scale.is_finite() && self.time_scale > 0.0 {
            Duration::try_from_secs_f64(d.as_secs_f64() * self.time_scale).unwrap_or(MAX_DEADLINE)
        } else {
            d
        };
        scaled.saturating_add(self.deadline_slack).min(MAX_DEADLINE)
    }
}

/// Longest deadline a run uses, whatever the scaling: 1000 h, the longest a scenario can ask
/// for (an hour) times the largest `--time-scale` (1000), and far from the overflow of an
/// `Instant` plus a `Duration` (a panic) that an unbounded deadline risks.
pub const MAX_DEADLINE: Duration = Duration::from_secs(1000 * 3600);

/// Largest `--time-scale` factor: a VM under full emulation runs ~100× slower than the host;
/// ten times that still leaves room, and more only turns typos into runs that never end.
pub const MAX_TIME_SCALE: f64 = 1000.0;
