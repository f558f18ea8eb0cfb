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
        Ok(Self { fd })
    }

    /// Sleeps until `deadline`. Cancel-safe: the next call re-arms the timer and discards an
    /// expiry left over from a cancelled sleep.
    pub(super) async fn sleep_until(&mut self, deadline: Instant) -> io::Result<()> {
        loop {
            let now = Instant::now();
            if now >= deadline {
                return Ok(());
            }
            self.drain();
            self.arm(deadline - now)?;
            let mut ready = self.fd.readable().await?;
            ready.clear_ready();
        }
    }

    /// Reads away a pending expiry count so the descriptor reads as not ready.
    fn drain(&self) {
        let mut count = [0u8; 8];
        // SAFETY: reads at most 8 bytes into a buffer of 8; a non-blocking timerfd with no
        // expiry fails with EAGAIN, which is fine.
        #[allow(unsafe_code)]
        let _ = unsafe {
            libc::read(
                self.fd.get_ref().as_raw_fd(),
                count.as_mut_ptr().cast(),
                count.len(),
            )
        };
    }

    /// One expiry `after` from now (at least a nanosecond: zero would disarm it).
    fn arm(&self, after: std::time::Duration) -> io::Result<()> {
        let nanos = after.as_nanos().max(1);
        let spec = libc::itimerspec {
            it_interval: libc::timespec {
                tv_sec: 0,
                tv_nsec: 0,
            },
            it_value: libc::timespec {
                tv_sec: libc::time_t::try_from(nanos / 1_000_000_000).unwrap_or(libc::time_t::MAX),
                tv_nsec: (nanos % 1_000_000_000) as libc::c_long,
            },
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
