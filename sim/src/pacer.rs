//! Periodic wake-ups for an emulator's clock task, on absolute deadlines in real time.
//!
//! tokio's timer wheel has a 1 ms resolution and rounds every sleep up to the next tick, so an
//! `interval` of 1 ms or 5 ms wakes up to a millisecond late and unevenly: the Piper's 200 Hz
//! feedback had a p99 period error of +0.4 ms idle and +0.8 to +2.2 ms with every core busy
//! (`cargo bench --bench realtime_jitter`). In real time a [`Pacer`] instead follows the
//! kernel's high-resolution clock:
//!
//! - **kernel timer** (default on a multi-thread runtime, Linux): a periodic timerfd that
//!   tokio's I/O driver watches ([`bus::fine_timer::PeriodicTimer`]). The worker that sees the
//!   expiry runs the step itself: no thread hop between the timer and the work, and one
//!   thread fewer to wake a thousand times a second at rest. The runtime's workers ask the
//!   fair scheduler for a short slice ([`prefer_punctual_thread`]), so a worker woken on
//!   time preempts a busy thread instead of waiting out its slice.
//! - **deadline thread** (`ARMHIL_PACER=thread`, or where no timerfd exists): one small
//!   thread that sleeps until each absolute deadline (`clock_nanosleep(CLOCK_MONOTONIC,
//!   TIMER_ABSTIME)`, 1 ns timer slack) and wakes the clock task through a [`Notify`]; the
//!   step runs on whichever worker picks the task up.
//! - **tokio's interval** (`ARMHIL_PACER=tokio`, current-thread runtimes, and a paused clock:
//!   virtual time and tests, which tokio's paused clock advances deterministically).
//!
//! `ARMHIL_REALTIME_PRIORITY=1` gives the deadline thread and the workers a low real-time
//! (FIFO) priority instead of the short slice (see [`prefer_punctual_thread`] for why not by
//! default). Missed deadlines are skipped, not bunched: the clock task works out how many
//! steps are due from elapsed time, so a wake-up is a prompt, not a count.
//!
//! A clock task takes its time origin *before* it makes its pacer: wake-ups then fall just
//! after each step's instant, so the count of steps due does not flip with timer jitter (with
//! the pacer made first, a step often ran a millisecond late).
//!
//! What that buys depends on the host's scheduler more than on this code; the figures
//! measured by `cargo bench --bench realtime_jitter` are in `docs/timing.md`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::Duration;

use tokio::runtime::RuntimeFlavor;
use tokio::sync::Notify;
use tokio::time::{interval, Interval, MissedTickBehavior};

/// Wakes its owner once per period; see the module docs for which clock it follows.
#[derive(Debug)]
pub struct Pacer {
    inner: Inner,
}

#[derive(Debug)]
enum Inner {
    /// tokio's timer: deterministic under a paused clock.
    Tokio(Interval),
    /// A periodic timerfd the runtime's I/O driver watches: the worker that sees the expiry
    /// runs the step.
    #[cfg(target_os = "linux")]
    Timer {
        timer: bus::fine_timer::PeriodicTimer,
        period: Duration,
    },
    /// A deadline thread that notifies.
    Thread {
        woken: Arc<Notify>,
        stop: Arc<AtomicBool>,
    },
}

/// Which clock a [`Pacer`] follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PacerKind {
    /// tokio's interval (virtual time, or a current-thread runtime).
    TokioTimer,
    /// A periodic timerfd on the runtime's I/O driver (real time on a multi-thread runtime,
    /// Linux).
    KernelTimer,
    /// A thread sleeping to absolute deadlines (`ARMHIL_PACER=thread`, or where no timerfd
    /// exists).
    DeadlineThread,
}

impl Pacer {
    /// A pacer with `period` between wake-ups, the first one at once, chosen by the
    /// current runtime's flavour (see the module docs). `name` names the deadline thread when
    /// there is one, for `top -H` and debuggers. Must be called inside a tokio runtime.
    ///
    /// On a multi-thread runtime the kernel timer (Linux), unless `ARMHIL_PACER`
    /// ([`PACER_ENV`]) asks for `kernel`, `thread` (a deadline thread) or `tokio` (tokio's
    /// timer).
    pub fn new(period: Duration, name: &str) -> Self {
        let multi_thread = tokio::runtime::Handle::try_current()
            .is_ok_and(|h| h.runtime_flavor() == RuntimeFlavor::MultiThread);
        if !multi_thread {
            return Self::tokio_timer(period);
        }
        match asked_pacer().unwrap_or(DEFAULT_PACER) {
            PacerKind::TokioTimer => Self::tokio_timer(period),
            PacerKind::DeadlineThread => Self::on_deadline_thread(period, name),
            PacerKind::KernelTimer => {
                Self::kernel_timer(period).unwrap_or_else(|| Self::on_deadline_thread(period, name))
            }
        }
    }

    /// A pacer on a periodic timerfd; `None` where there is none (not Linux, or the runtime
    /// has no I/O driver), after a warning.
    #[cfg(target_os = "linux")]
    fn kernel_timer(period: Duration) -> Option<Self> {
        match bus::fine_timer::PeriodicTimer::new(period) {
            Ok(timer) => Some(Self {
                inner: Inner::Timer { timer, period },
            }),
            Err(e) => {
                tracing::warn!(error = %e, "no kernel timer: pacing on a deadline thread");
                None
            }
        }
    }

    #[cfg(not(target_os = "linux"))]
    fn kernel_timer(_period: Duration) -> Option<Self> {
        None
    }

    /// A pacer on its own deadline thread whatever the environment says (tests, benches);
    /// tokio's timer if the thread cannot be started. Must be called inside a multi-thread
    /// runtime to make sense.
    pub fn on_deadline_thread(period: Duration, name: &str) -> Self {
        Self::deadline_thread(period, name).unwrap_or_else(|| Self::tokio_timer(period))
    }

    /// A pacer on tokio's timer whatever the runtime.
    pub fn tokio_timer(period: Duration) -> Self {
        let mut ticks = interval(period);
        ticks.set_missed_tick_behavior(MissedTickBehavior::Skip);
        Self {
            inner: Inner::Tokio(ticks),
        }
    }

    /// A pacer on its own deadline thread; `None` when the thread cannot be started (the
    /// caller falls back to tokio's timer rather than failing the emulator).
    fn deadline_thread(period: Duration, name: &str) -> Option<Self> {
        let woken = Arc::new(Notify::new());
        let stop = Arc::new(AtomicBool::new(false));
        let (thread_woken, thread_stop) = (Arc::clone(&woken), Arc::clone(&stop));
        let spawned = thread::Builder::new()
            .name(name.to_string())
            .spawn(move || deadline_loop(period, &thread_woken, &thread_stop));
        match spawned {
            Ok(_) => Some(Self {
                inner: Inner::Thread { woken, stop },
            }),
            Err(e) => {
                tracing::warn!(error = %e, "no deadline thread: pacing on tokio's 1 ms timer");
                None
            }
        }
    }

    /// Which clock this pacer follows.
    pub fn kind(&self) -> PacerKind {
        match self.inner {
            Inner::Tokio(_) => PacerKind::TokioTimer,
            #[cfg(target_os = "linux")]
            Inner::Timer { .. } => PacerKind::KernelTimer,
            Inner::Thread { .. } => PacerKind::DeadlineThread,
        }
    }

    /// Waits for the next wake-up. Cancel-safe: dropping the future loses no wake-up that has
    /// not happened yet, and one that happened while nobody waited is kept (at most one).
    pub async fn tick(&mut self) {
        match &mut self.inner {
            Inner::Tokio(ticks) => {
                ticks.tick().await;
            }
            #[cfg(target_os = "linux")]
            Inner::Timer { timer, period } => {
                // An owner that is late would find its expiry ready at once and never give the
                // worker back (see the deadline thread's permit below): yield first then. Not
                // on time: a yield costs the worker an extra poll of the I/O driver and wakes
                // its sibling, a third of the runtime's work at rest.
                if timer.is_overdue() {
                    tokio::task::yield_now().await;
                }
                if let Err(e) = timer.tick().await {
                    tracing::warn!(error = %e, "the kernel timer failed: pacing on tokio's timer");
                    *self = Self::tokio_timer(*period);
                }
            }
            Inner::Thread { woken, .. } => {
                // A wake-up that came while the owner was busy is kept as a permit, and then
                // `notified()` is ready at once, without giving the worker back: an owner
                // slower than its period (a machine too slow for real time) would loop
                // forever, and the tasks it wakes (its transmitter, parked in the worker's
                // slot that other workers cannot steal from) would never run. Found in the
                // TCG test VM, where the Piper's clients then never got a frame.
                tokio::task::yield_now().await;
                woken.notified().await;
            }
        }
    }
}

impl Drop for Pacer {
    fn drop(&mut self) {
        if let Inner::Thread { stop, .. } = &self.inner {
            // The thread sees the flag at its next deadline and ends.
            stop.store(true, Ordering::Relaxed);
        }
    }
}

/// Worker threads of [`real_time_runtime`]. One: on this project's 2-core machine, with every
/// core busy, the Piper's 200 Hz period stayed within +0.17 ms in ten runs of ten with one
/// worker, where two workers on the same timer strayed to +2.5 ms in one run of six (`cargo
/// bench --bench realtime_jitter`); and the humanoid under 2,000 commands/s took 16-21 % of a
/// core instead of 20-24 % (`cargo bench --bench wire_latency`): with two, the worker that saw
/// a timer or a socket often woke its sibling to share the work, and each hand-over cost a task
/// switch (half the samples of a profile under load). An emulator's work fits one core with
/// room to spare; figures in `docs/timing.md`.
pub const REAL_TIME_WORKERS: usize = 1;

/// The runtime a real-time emulator runs on, as `armhil sim` starts it: [`REAL_TIME_WORKERS`]
/// worker, made punctual ([`prefer_punctual_thread`]), timers and I/O enabled. Benches that
/// measure `armhil sim`'s timing in-process start the same one.
///
/// # Errors
/// The operating system's, when the worker thread or the I/O driver cannot be created.
pub fn real_time_runtime() -> std::io::Result<tokio::runtime::Runtime> {
    real_time_runtime_builder().build()
}

/// The builder of [`real_time_runtime`], for a host that adds its own settings (the Python
/// package names its threads).
pub fn real_time_runtime_builder() -> tokio::runtime::Builder {
    let mut builder = tokio::runtime::Builder::new_multi_thread();
    builder
        .worker_threads(REAL_TIME_WORKERS)
        .on_thread_start(prefer_punctual_thread)
        .enable_all();
    builder
}

/// The environment variable that lets an emulator's deadline thread and runtime workers take
/// a real-time priority (`1`): see [`prefer_punctual_thread`].
pub const REALTIME_PRIORITY_ENV: &str = "ARMHIL_REALTIME_PRIORITY";

/// Asks the kernel to run the calling thread on time, for the worker threads of a real-time
/// emulator's runtime (`Builder::on_thread_start`): the timer wakes a worker on time, but a
/// busy core can make it wait for its turn. Always 1 ns timer slack; by default a 0.1 ms
/// fair-scheduler slice (no privilege needed; Linux 6.12 and later honour it), with which a
/// woken worker preempts a thread using its longer slice. With `ARMHIL_REALTIME_PRIORITY=1`
/// (and the privilege) the low FIFO priority instead, which the deadline thread then takes
/// too. FIFO is not the default: FIFO workers doing a step's real work take the CPU from
/// every normal thread, and on a machine too slow for real time (the project's two-vCPU
/// emulated test VM) the emulator's clients starved and timed out. Figures in
/// `docs/timing.md`.
pub fn prefer_punctual_thread() {
    deadline::prefer_punctual(realtime_priority_asked());
}

/// Whether `ARMHIL_REALTIME_PRIORITY=1` is set.
fn realtime_priority_asked() -> bool {
    std::env::var(REALTIME_PRIORITY_ENV).is_ok_and(|v| v.trim() == "1")
}

/// The environment variable that chooses another pacer for real-time emulators: `tokio`
/// (tokio's 1 ms timer), `thread` (a deadline thread) or `kernel` (a kernel timer); unset,
/// the default for the clock's period.
pub const PACER_ENV: &str = "ARMHIL_PACER";

/// The real-time pacer when the environment asks for none: the kernel timer, whatever the
/// clock's period. The Piper's clock (five steps per wake-up) had a deadline thread until
/// 2026-12-07: on the project's 2-core machine with every core busy the thread's p99 period
/// error was +0.7 to +2.8 ms in six runs of six, the kernel timer's +0.09 to +0.17 ms in ten
/// of ten (one worker, `cargo bench --bench realtime_jitter`). The thread had been kept for
/// the emulated (TCG) test VM, where the vendor SDK saw its arm disabled after 12, 18, 49 and
/// over 60 s with it and 20 s in the one run with the kernel timer: it was never the better.
const DEFAULT_PACER: PacerKind = PacerKind::KernelTimer;

/// The pacer `ARMHIL_PACER` asks for, if it names one.
fn asked_pacer() -> Option<PacerKind> {
    match std::env::var(PACER_ENV).ok()?.trim() {
        "tokio" => Some(PacerKind::TokioTimer),
        "thread" => Some(PacerKind::DeadlineThread),
        "kernel" => Some(PacerKind::KernelTimer),
        other => {
            tracing::warn!(
                value = other,
                "{PACER_ENV} is one of tokio, thread, kernel; ignored"
            );
            None
        }
    }
}

/// The deadline thread's body: sleep to each deadline, notify, until `stop`.
fn deadline_loop(period: Duration, woken: &Notify, stop: &AtomicBool) {
    deadline::prefer_punctual(realtime_priority_asked());
    let mut clock = deadline::Clock::start();
    // The first wake-up at once, as tokio's `interval` fires its first tick at once.
    woken.notify_one();
    while !stop.load(Ordering::Relaxed) {
        clock.sleep_until_next(period);
        // `notify_one` keeps one permit when nobody waits: a slow clock task finds one wake-up
        // waiting, never a backlog.
        woken.notify_one();
    }
}

#[cfg(target_os = "linux")]
mod deadline {
    //! Absolute deadlines on CLOCK_MONOTONIC, the clock `std::time::Instant` reads on Linux.
    //! libc's `clock_nanosleep` directly: std has no absolute sleep, and the timer crates
    //! (timerfd, spin_sleep) add a file descriptor or a busy loop for what is one call.

    use std::time::Duration;

    const NANOS_PER_SEC: i64 = 1_000_000_000;

    /// The next deadline, as the kernel counts it.
    pub(super) struct Clock {
        next: libc::timespec,
    }

    impl Clock {
        /// Deadlines counted from now.
        pub(super) fn start() -> Self {
            Self { next: now() }
        }

        /// Advances the deadline by `period` and sleeps until it. A deadline already past by
        /// more than a period (the machine stalled) moves to one period from now: missed
        /// wake-ups are skipped, as tokio's `MissedTickBehavior::Skip` does.
        pub(super) fn sleep_until_next(&mut self, period: Duration) {
            let period_ns = i64::try_from(period.as_nanos()).unwrap_or(i64::MAX);
            self.next = add_ns(self.next, period_ns);
            let now = now();
            if ns_between(self.next, now) > period_ns {
                self.next = add_ns(now, period_ns);
            }
            loop {
                // SAFETY: `self.next` is a valid timespec and the remainder pointer may be null
                // for an absolute sleep.
                #[allow(unsafe_code)]
                let rc = unsafe {
                    libc::clock_nanosleep(
                        libc::CLOCK_MONOTONIC,
                        libc::TIMER_ABSTIME,
                        &self.next,
                        std::ptr::null_mut(),
                    )
                };
                // EINTR: a signal arrived first; the deadline is absolute, so sleep again.
                if rc != libc::EINTR {
                    break;
                }
            }
        }
    }

    /// 1 ns timer slack, and with `fifo` the low real-time priority, else a short slice
    /// (best effort).
    pub(super) fn prefer_punctual(fifo: bool) {
        // SAFETY: plain syscalls on the calling thread with valid arguments.
        #[allow(unsafe_code)]
        unsafe {
            libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong);
            let param = libc::sched_param { sched_priority: 10 };
            if fifo && libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) != 0 {
                tracing::debug!("no real-time priority, staying in the normal class");
            }
        }
        if !fifo {
            request_short_slice();
        }
    }

    /// `struct sched_attr` of `sched_setattr(2)` (its first version, 56 bytes), which libc
    /// does not define.
    #[repr(C)]
    #[derive(Default)]
    struct SchedAttr {
        size: u32,
        policy: u32,
        flags: u64,
        nice: i32,
        priority: u32,
        runtime_ns: u64,
        deadline_ns: u64,
        period_ns: u64,
    }

    /// The slice a normal-class thread asks for: the shortest the kernel accepts.
    const SHORT_SLICE_NS: u64 = 100_000;

    /// Asks the fair scheduler for a 0.1 ms slice instead of its default of a few. Since
    /// Linux 6.12 (EEVDF) a thread's `sched_runtime` is its slice, which needs no privilege,
    /// and a waking thread with a short slice gets an early deadline and preempts a thread
    /// that is using its long one: a step woken on time then runs on time though every core
    /// is busy. Older kernels ignore the field. The thread's policy and nice value are kept.
    fn request_short_slice() {
        let mut attr = SchedAttr::default();
        let size = std::mem::size_of::<SchedAttr>() as u32;
        // SAFETY: `attr` is a valid, writable sched_attr of `size` bytes for the calling thread.
        #[allow(unsafe_code)]
        let read = unsafe {
            libc::syscall(
                libc::SYS_sched_getattr,
                0,
                &mut attr as *mut SchedAttr,
                size,
                0,
            )
        };
        if read != 0 || attr.policy != libc::SCHED_OTHER as u32 {
            return;
        }
        attr.size = size;
        attr.runtime_ns = SHORT_SLICE_NS;
        // SAFETY: as above, read-only for the kernel.
        #[allow(unsafe_code)]
        let set =
            unsafe { libc::syscall(libc::SYS_sched_setattr, 0, &attr as *const SchedAttr, 0) };
        if set != 0 {
            tracing::debug!(
                "no short scheduler slice: {}",
                std::io::Error::last_os_error()
            );
        }
    }

    fn now() -> libc::timespec {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `t` is a valid out-pointer; CLOCK_MONOTONIC always exists on Linux.
        #[allow(unsafe_code)]
        unsafe {
            libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t);
        }
        t
    }

    // `time_t` and `c_long` are i64 on 64-bit Linux but i32 on some 32-bit targets: the
    // conversions are needed there.
    #[allow(clippy::useless_conversion, clippy::unnecessary_cast)]
    fn add_ns(t: libc::timespec, ns: i64) -> libc::timespec {
        let total = i64::from(t.tv_nsec) + ns % NANOS_PER_SEC;
        libc::timespec {
            tv_sec: t.tv_sec + (ns / NANOS_PER_SEC + total / NANOS_PER_SEC) as libc::time_t,
            tv_nsec: (total % NANOS_PER_SEC) as libc::c_long,
        }
    }

    /// `later − earlier` in ns (negative when `later` is earlier).
    #[allow(clippy::unnecessary_cast)]
    fn ns_between(earlier: libc::timespec, later: libc::timespec) -> i64 {
        (later.tv_sec as i64 - earlier.tv_sec as i64) * NANOS_PER_SEC
            + (later.tv_nsec as i64 - earlier.tv_nsec as i64)
    }

    #[cfg(test)]
    #[allow(clippy::unnecessary_cast)] // see `add_ns`
    mod tests {
        use super::*;

        fn ts(sec: i64, nsec: i64) -> libc::timespec {
            libc::timespec {
                tv_sec: sec as libc::time_t,
                tv_nsec: nsec as libc::c_long,
            }
        }

        #[test]
        fn adding_carries_nanoseconds_into_seconds() {
            let t = add_ns(ts(7, 999_500_000), 1_000_000);
            assert_eq!((t.tv_sec as i64, t.tv_nsec as i64), (8, 500_000));
            let t = add_ns(ts(7, 0), 2_500_000_000);
            assert_eq!((t.tv_sec as i64, t.tv_nsec as i64), (9, 500_000_000));
            assert_eq!(ns_between(ts(7, 999_500_000), ts(8, 500_000)), 1_000_000);
            assert_eq!(ns_between(ts(8, 500_000), ts(7, 999_500_000)), -1_000_000);
        }
    }
}

#[cfg(not(target_os = "linux"))]
mod deadline {
    //! Elsewhere: a relative sleep to each absolute deadline (no drift, coarser wake-ups).

    use std::time::{Duration, Instant};

    pub(super) struct Clock {
        next: Instant,
    }

    /// No priority hints off Linux.
    pub(super) fn prefer_punctual(_fifo: bool) {}

    impl Clock {
        pub(super) fn start() -> Self {
            Self {
                next: Instant::now(),
            }
        }

        pub(super) fn sleep_until_next(&mut self, period: Duration) {
            self.next += period;
            let now = Instant::now();
            if now.saturating_duration_since(self.next) > period {
                self.next = now + period;
            }
            std::thread::sleep(self.next.saturating_duration_since(now));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_owner_slower_than_its_period_still_lets_the_tasks_it_wakes_run() {
        slow_owner_lets_woken_tasks_run(|| {
            Pacer::on_deadline_thread(Duration::from_millis(1), "test-slow")
        });
        #[cfg(target_os = "linux")]
        slow_owner_lets_woken_tasks_run(|| {
            let pacer = Pacer::kernel_timer(Duration::from_millis(1)).expect("a timerfd");
            assert_eq!(pacer.kind(), PacerKind::KernelTimer);
            pacer
        });
    }

    fn slow_owner_lets_woken_tasks_run(make: fn() -> Pacer) {
        use std::sync::atomic::AtomicUsize;
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .expect("runtime");
        let wake_ups = rt.block_on(async {
            let seen = Arc::new(AtomicUsize::new(0));
            let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel::<()>();
            let counted = Arc::clone(&seen);
            tokio::spawn(async move {
                while rx.recv().await.is_some() {
                    counted.fetch_add(1, Ordering::Relaxed);
                }
            });
            let clock = tokio::spawn(async move {
                let mut pacer = make();
                // Until the woken task has seen ten messages, or 200 wake-ups if it never runs.
                let mut wake_ups = 0;
                while wake_ups < 200 && seen.load(Ordering::Relaxed) < 10 {
                    pacer.tick().await;
                    wake_ups += 1;
                    // Each wake-up's work takes three periods, as a step does in a slow VM.
                    std::thread::sleep(Duration::from_millis(3));
                    let _ = tx.send(());
                }
                wake_ups
            });
            clock.await.expect("the clock task ends")
        });
        assert!(
            wake_ups < 30,
            "the woken task ran alongside: its tenth message after {wake_ups} wake-ups"
        );
    }

    #[test]
    fn a_paused_clock_gets_tokio_timer_and_real_time_a_kernel_timer() {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .start_paused(true)
            .build()
            .expect("runtime");
        rt.block_on(async {
            let mut pacer = Pacer::new(Duration::from_millis(5), "test-pacer");
            assert_eq!(pacer.kind(), PacerKind::TokioTimer);
            let t0 = tokio::time::Instant::now();
            for _ in 0..4 {
                pacer.tick().await;
            }
            // Virtual time: the first wake-up at once, then exactly three periods.
            assert_eq!(t0.elapsed(), Duration::from_millis(15));
        });
        // The runtime `armhil sim` runs its emulators on.
        let rt = real_time_runtime().expect("runtime");
        rt.block_on(async {
            let made: [fn() -> Pacer; 2] = [
                || Pacer::on_deadline_thread(Duration::from_millis(1), "test-pacer"),
                || Pacer::new(Duration::from_millis(1), "test-pacer"),
            ];
            let mut kinds = Vec::new();
            for make in made {
                // Timed from before it is made: its deadlines count from when it was made.
                let t0 = std::time::Instant::now();
                let mut pacer = make();
                kinds.push(pacer.kind());
                for _ in 0..10 {
                    pacer.tick().await;
                }
                // The first wake-up at once, then nine deadlines 1 ms apart: not before
                // 9 ms; no upper bound, as this machine may be loaded.
                assert!(
                    t0.elapsed() >= Duration::from_millis(9),
                    "{:?} {:?}",
                    pacer.kind(),
                    t0.elapsed()
                );
            }
            // A clock of several milliseconds per wake-up (the Piper's) takes the kernel timer
            // too: it kept time where the deadline thread did not (`DEFAULT_PACER`).
            kinds.push(Pacer::new(Duration::from_millis(5), "test-pacer").kind());
            #[cfg(target_os = "linux")]
            assert_eq!(
                kinds,
                [
                    PacerKind::DeadlineThread,
                    PacerKind::KernelTimer,
                    PacerKind::KernelTimer
                ]
            );
            #[cfg(not(target_os = "linux"))]
            assert_eq!(kinds, [PacerKind::DeadlineThread; 3]);
        });
    }
}
