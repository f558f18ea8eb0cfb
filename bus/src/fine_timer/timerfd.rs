//! A timerfd watched by tokio's I/O driver: wake-ups on the kernel's high-resolution clock.
//!
//! libc directly rather than a timer crate: the whole of it is `timerfd_create`,
//! `timerfd_settime` and a read, and tokio's `AsyncFd` already does the waiting; the crates
//! that wrap it add their own reactor or a dependency on an older tokio.

use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};

use tokio::io::unix::AsyncFd;
use tokio::time::Instant;

/// One task's timer.
#[derive(Debug)]
pub(super) struct TimerFd {
    fd: AsyncFd<OwnedFd>,
    /// How late this machine's timer wakes the task: [`TimerFd::sleep_until`] arms that much
    /// early.
    lateness: WakeLateness,
}

impl TimerFd {
    /// A disarmed timer on CLOCK_MONOTONIC, the clock `Instant` reads on Linux. Needs a
    /// runtime with I/O enabled.
    pub(super) fn new() -> io::Result<Self> {
        // SAFETY: plain system call with constant arguments; the result is checked.
        #[allow(unsafe_code)]
        let raw = unsafe {
            libc::timerfd_create(
                libc::CLOCK_MONOTONIC,
                libc::TFD_NONBLOCK | libc::TFD_CLOEXEC,
            )
        };
        if raw < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: `raw` is a descriptor this function just opened and nothing else owns.
        #[allow(unsafe_code)]
        let owned = unsafe { OwnedFd::from_raw_fd(raw) };
        // SAFETY: an OwnedFd always returns the descriptor it owns, which stays open until
        // the AsyncFd that now owns it is dropped.
        #[allow(unsafe_code)]
        let fd = unsafe { AsyncFd::register_with_interest(owned, tokio::io::Interest::READABLE) }
            .map_err(|refused| refused.into_parts().1)?;
        Ok(Self {
            fd,
            lateness: WakeLateness::default(),
        })
    }

    /// Sleeps until `deadline`: the timer is armed [`WakeLateness::advance`] early and the
    /// rest of the wait, when the wake-up comes before the deadline, is spun. Cancel-safe:
    /// the next call re-arms the timer and discards an expiry left over from a cancelled
    /// sleep (the spin never awaits).
    pub(super) async fn sleep_until(&mut self, deadline: Instant) -> io::Result<()> {
        loop {
            let now = Instant::now();
            if now >= deadline {
                return Ok(());
            }
            let armed_for = deadline
                .checked_sub(self.lateness.advance())
                .unwrap_or(deadline);
            if armed_for <= now {
                spin_until(deadline);
                return Ok(());
            }
            self.drain();
            self.arm(armed_for - now)?;
            let mut ready = self.fd.readable().await?;
            ready.clear_ready();
            let woke = Instant::now();
            // Readiness left over from an earlier expiry: arm again.
            if woke < armed_for {
                continue;
            }
            self.lateness.observe(woke - armed_for);
            spin_until(deadline);
            return Ok(());
        }
    }

    /// Reads away a pending expiry count so the descriptor reads as not ready.
    fn drain(&self) {
        let _ = self.read_count();
    }

    /// The expiries since the last read, or `None` when there was none (the non-blocking
    /// read fails with EAGAIN).
    fn read_count(&self) -> Option<u64> {
        let mut count = [0u8; 8];
        // SAFETY: reads at most 8 bytes into a buffer of 8; a non-blocking timerfd with no
        // expiry fails with EAGAIN, which is fine.
        #[allow(unsafe_code)]
        let read = unsafe {
            libc::read(
                self.fd.get_ref().as_raw_fd(),
                count.as_mut_ptr().cast(),
                count.len(),
            )
        };
        (read == 8).then(|| u64::from_ne_bytes(count))
    }

    /// One expiry `after` from now (at least a nanosecond: zero would disarm it).
    fn arm(&self, after: std::time::Duration) -> io::Result<()> {
        self.set(after, std::time::Duration::ZERO)
    }

    /// First expiry `after` from now (at least a nanosecond), then one every `period` (zero:
    /// none). The kernel keeps the period's phase, so wake-ups do not drift with the time
    /// their owner takes.
    fn set(&self, after: std::time::Duration, period: std::time::Duration) -> io::Result<()> {
        let spec = libc::itimerspec {
            it_interval: timespec(period),
            it_value: timespec(after.max(std::time::Duration::from_nanos(1))),
        };
        // SAFETY: valid descriptor and itimerspec; the old value pointer may be null.
        #[allow(unsafe_code)]
        let rc = unsafe {
            libc::timerfd_settime(
                self.fd.get_ref().as_raw_fd(),
                0,
                &spec,
                std::ptr::null_mut(),
            )
        };
        if rc < 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(())
    }
}

/// Busy-waits until `deadline`; callers bound the wait by [`WakeLateness::MAX_ADVANCE`].
fn spin_until(deadline: Instant) {
    while Instant::now() < deadline {
        std::hint::spin_loop();
    }
}

/// A running estimate of how late the timer wakes a task that sleeps on it: a low quantile of
/// the lateness seen, learnt one wake-up at a time.
///
/// Why: a timer wake-up is never on time. On the project's virtual machines the median is
/// about 40-50 µs late (the host's own timer slack and the virtual CPU's wake-up), and each
/// CAN exchange the virtual bus times takes two wake-ups: request off the wire, answer off the
/// wire. Arming early by what the timer nearly always loses and spinning the remainder puts
/// the frame where the wire model says, at the cost of a short spin when a wake-up happens to
/// come early (the trade KVM makes with its timer advance). On a machine whose timer is
/// punctual the estimate stays near zero and nothing spins.
///
/// The estimate follows the 10th percentile (a step up of [`Self::STEP_UP`] on a later
/// wake-up, nine times that down on an earlier one: at the quantile the two balance). Not
/// the median: a wake-up is also late when the one runtime worker was busy with another task,
/// and an estimate that learnt those delays spins whenever the worker is free — with the 25th
/// percentile the humanoid's wire tasks spun a fifth of the process's time under load
/// (`cargo bench --bench wire_latency`). An outlier moves the estimate by one step only, and
/// [`Self::MAX_ADVANCE`] bounds the spin on a machine whose timer is far off.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(super) struct WakeLateness {
    estimate: std::time::Duration,
}

impl WakeLateness {
    /// The estimate's step up on a wake-up later than it.
    pub(super) const STEP_UP: std::time::Duration = std::time::Duration::from_nanos(250);
    /// Its step down on an earlier one: nine steps up, so it settles where one wake-up in ten
    /// comes earlier.
    const STEP_DOWN: std::time::Duration = std::time::Duration::from_nanos(2_250);
    /// The most the timer is armed early, so the most a sleep spins.
    pub(super) const MAX_ADVANCE: std::time::Duration = std::time::Duration::from_micros(60);

    /// Learns from one wake-up that came `late` after the instant the timer was armed for.
    pub(super) fn observe(&mut self, late: std::time::Duration) {
        self.estimate = if late > self.estimate {
            (self.estimate + Self::STEP_UP).min(Self::MAX_ADVANCE)
        } else {
            self.estimate.saturating_sub(Self::STEP_DOWN)
        };
    }

    /// How early to arm the timer.
    pub(super) fn advance(&self) -> std::time::Duration {
        self.estimate
    }
}

fn timespec(d: std::time::Duration) -> libc::timespec {
    libc::timespec {
        tv_sec: libc::time_t::try_from(d.as_secs()).unwrap_or(libc::time_t::MAX),
        // Below 10^9: fits every c_long.
        tv_nsec: d.subsec_nanos() as libc::c_long,
    }
}

/// A timer that fires every period, for a task that must wake on a fixed cadence (an
/// emulator's control loop): the task runs on the runtime worker whose I/O driver saw the
/// expiry, with no thread between the kernel's timer and the work.
#[derive(Debug)]
pub struct PeriodicTimer {
    timer: TimerFd,
    /// When the first expiry was due.
    first: std::time::Instant,
    period: std::time::Duration,
    /// Expiries returned so far.
    seen: u64,
}

impl PeriodicTimer {
    /// A timer whose first expiry is now and then one every `period`. Needs a tokio runtime
    /// with I/O enabled.
    pub fn new(period: std::time::Duration) -> io::Result<Self> {
        let timer = TimerFd::new()?;
        let first = std::time::Instant::now();
        timer.set(std::time::Duration::ZERO, period)?;
        Ok(Self {
            timer,
            first,
            period,
            seen: 0,
        })
    }

    /// Whether the next expiry is already due, so that [`PeriodicTimer::tick`] will return
    /// without waiting: its owner is late. Reads the clock, not the descriptor.
    pub fn is_overdue(&self) -> bool {
        let next = u32::try_from(self.seen)
            .ok()
            .and_then(|n| self.period.checked_mul(n))
            .and_then(|since| self.first.checked_add(since));
        next.is_none_or(|next| std::time::Instant::now() >= next)
    }

    /// Waits for the next expiry and returns how many periods ended since the last call (more
    /// than one when the owner was late: the missed ones are reported, not replayed).
    /// Cancel-safe: an expiry that happened while nobody waited is returned by the next call.
    pub async fn tick(&mut self) -> io::Result<u64> {
        loop {
            let mut ready = self.timer.fd.readable().await?;
            let count = self.timer.read_count();
            // Cleared either way, so the next call waits in the driver rather than paying a
            // read that finds nothing. Safe: tokio clears only the readiness this guard saw;
            // an expiry after the read arrives as a new event.
            ready.clear_ready();
            if let Some(count) = count {
                self.seen = self.seen.saturating_add(count);
                return Ok(count);
            }
        }
    }
}
