//! Sleeping to a deadline finer than tokio's timer.
//!
//! tokio's timer wheel counts whole milliseconds and rounds every deadline up to the next
//! one, in real time and under a paused clock alike. A CAN frame takes about 0.13 ms at
//! 1 Mbit/s and a motor's firmware answers a fraction of a millisecond later, so a bus that
//! wakes on tokio's timer delivers a frame up to a millisecond after its last bit and every
//! request/reply round trip costs at least two ticks. The virtual bus's wire task sleeps
//! through a [`FineTimer`] instead:
//!
//! - in **real time** on a multi-thread runtime (Linux): a timerfd the runtime's I/O driver
//!   watches, which the kernel fires on its high-resolution clock (tens of microseconds late,
//!   not a millisecond);
//! - in **virtual time**: a [`VirtualTimeline`], which moves a paused clock to each
//!   sub-millisecond deadline itself, so a frame arrives and an answer leaves at the
//!   microsecond the wire model says, and runs stay deterministic;
//! - otherwise tokio's timer (a current-thread runtime nobody drives finer, tests that pause
//!   the clock without a timeline).
//!
//! [`PeriodicTimer`] (Linux) is the same timerfd firing on a fixed period, for the real-time
//! control loops of emulators.

mod timeline;
#[cfg(target_os = "linux")]
mod timerfd;

use tokio::runtime::RuntimeFlavor;
use tokio::time::Instant;

pub use timeline::{TimelineGuard, VirtualTimeline};
#[cfg(target_os = "linux")]
pub use timerfd::PeriodicTimer;

/// Which clock a bus's wire sleeps on; see the module docs.
#[derive(Debug, Clone, Default)]
pub enum FineTimer {
    /// Chosen when the bus starts: a timerfd on a multi-thread runtime (Linux), else
    /// tokio's timer.
    #[default]
    Auto,
    /// tokio's timer, whole milliseconds.
    Tokio,
    /// Sub-millisecond deadlines on a paused clock, driven by a [`VirtualTimeline`].
    Virtual(VirtualTimeline),
}

/// Two timers are the same choice (a configuration compares equal when it would behave the
/// same).
impl PartialEq for FineTimer {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Self::Auto, Self::Auto) | (Self::Tokio, Self::Tokio) => true,
            (Self::Virtual(a), Self::Virtual(b)) => a.same_as(b),
            _ => false,
        }
    }
}

impl FineTimer {
    /// The sleeper one task uses, resolving [`FineTimer::Auto`] on the current runtime.
    pub fn sleeper(&self) -> Sleeper {
        let inner = match self {
            Self::Virtual(timeline) => SleeperKind::Virtual(timeline.clone()),
            Self::Tokio => SleeperKind::Tokio,
            Self::Auto => Self::auto(),
        };
        Sleeper { inner }
    }

    #[cfg(target_os = "linux")]
    fn auto() -> SleeperKind {
        let multi_thread = tokio::runtime::Handle::try_current()
            .is_ok_and(|h| h.runtime_flavor() == RuntimeFlavor::MultiThread);
        if !multi_thread {
            return SleeperKind::Tokio;
        }
        match timerfd::TimerFd::new() {
            Ok(fd) => SleeperKind::TimerFd(fd),
            Err(error) => {
                tracing::warn!(%error, "no timerfd: the bus times frames on tokio's 1 ms timer");
                SleeperKind::Tokio
            }
        }
    }

    #[cfg(not(target_os = "linux"))]
    fn auto() -> SleeperKind {
        let _ = RuntimeFlavor::CurrentThread;
        SleeperKind::Tokio
    }
}

/// One task's way to sleep to a deadline (see [`FineTimer::sleeper`]).
#[derive(Debug)]
pub struct Sleeper {
    inner: SleeperKind,
}

#[derive(Debug)]
enum SleeperKind {
    Tokio,
    Virtual(VirtualTimeline),
    #[cfg(target_os = "linux")]
    TimerFd(timerfd::TimerFd),
}

impl Sleeper {
    /// Waits until `deadline` (at once when it has passed). Cancel-safe: a sleep dropped
    /// before its deadline leaves nothing behind that could wake the task later.
    pub async fn sleep_until(&mut self, deadline: Instant) {
        match &mut self.inner {
            SleeperKind::Tokio => tokio::time::sleep_until(deadline).await,
            SleeperKind::Virtual(timeline) => timeline.sleep_until(deadline).await,
            #[cfg(target_os = "linux")]
            SleeperKind::TimerFd(fd) => {
                if let Err(error) = fd.sleep_until(deadline).await {
                    tracing::warn!(%error, "timerfd failed: the bus times frames on tokio's 1 ms timer");
                    self.inner = SleeperKind::Tokio;
                    tokio::time::sleep_until(deadline).await;
                }
            }
        }
    }

    /// Whether this sleeper wakes finer than tokio's millisecond.
    pub fn is_fine(&self) -> bool {
        !matches!(self.inner, SleeperKind::Tokio)
    }
}

#[cfg(test)]
mod tests;
