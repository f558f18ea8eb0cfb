//! Virtual time finer than a millisecond on tokio's paused clock.
//!
//! A paused tokio clock moves only when every task waits, and then by whole milliseconds: its
//! timer wheel rounds each deadline up to the next tick and advances by tick counts. A
//! [`VirtualTimeline`] keeps its own sleepers with exact deadlines and one driver task that
//! moves the clock itself: when the tasks of this instant have run (a few scheduler rounds,
//! which the driver waits out by yielding, so the runtime never idles into its own advance),
//! it advances to the earliest of the next sleeper and the next millisecond boundary. Passing
//! every boundary exactly keeps tokio's own timers (the physics step, driver timeouts) on
//! their ticks; between boundaries only this timeline's sleepers wake. With no sleeper left it
//! lets the runtime idle and advance as it always did, which it can do exactly because the
//! clock then stands on a boundary.
//!
//! Same inputs, same schedule: the runtime is single-threaded and the driver's rounds are
//! counted, not timed, so runs stay deterministic.

use std::collections::BTreeMap;
use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::task::{Context, Poll, Waker};
use std::time::Duration;

use tokio::runtime::RuntimeFlavor;
use tokio::sync::Notify;
use tokio::task::JoinHandle;
use tokio::time::Instant;

/// Scheduler rounds the driver lets pass before it moves the clock: a frame's arrival wakes a
/// receiving task, which hands it to an emulator's loop, which queues the answer — each hop
/// normally within one round, the spare rounds for a busy runtime whose round was cut short
/// by tokio's polling budget.
const SETTLE_ROUNDS: usize = 3;

/// One millisecond, tokio's timer tick.
const TICK: Duration = Duration::from_millis(1);

/// Sub-millisecond deadlines on a paused clock; see the module docs. Cloning gives another
/// handle to the same timeline.
#[derive(Clone)]
pub struct VirtualTimeline {
    inner: Arc<Inner>,
}

struct Inner {
    /// Sleepers by (deadline, registration number): the earliest first, ties in order.
    sleepers: Mutex<BTreeMap<(Instant, u64), Waker>>,
    next_id: AtomicU64,
    /// Tells an idle driver that a sleeper arrived.
    registered: Notify,
    /// The instant the timeline started, on a millisecond boundary of tokio's clock.
    origin: Instant,
}

impl std::fmt::Debug for VirtualTimeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualTimeline")
            .field("sleepers", &self.inner.lock().len())
            .finish_non_exhaustive()
    }
}

/// Keeps a timeline's driver running; dropping it stops the driver (sleepers then wake on
/// the millisecond boundaries tokio's clock reaches on its own, never earlier).
#[derive(Debug)]
pub struct TimelineGuard {
    timeline: VirtualTimeline,
    driver: JoinHandle<()>,
}

impl TimelineGuard {
    /// The timeline, for buses to sleep on.
    pub fn timeline(&self) -> &VirtualTimeline {
        &self.timeline
    }
}

impl Drop for TimelineGuard {
    fn drop(&mut self) {
        self.driver.abort();
    }
}

impl Inner {
    fn lock(&self) -> MutexGuard<'_, BTreeMap<(Instant, u64), Waker>> {
        // A waker map stays consistent whatever panicked while holding it.
        self.sleepers
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl VirtualTimeline {
    /// Starts driving the current runtime's clock. `None` unless the runtime is a
    /// current-thread one whose clock is paused (real time needs no driver and must not get
    /// one). Call it before anything moves the clock by a fraction of a millisecond: the
    /// timeline's boundaries are counted from now.
    pub fn start() -> Option<TimelineGuard> {
        let handle = tokio::runtime::Handle::try_current().ok()?;
        if handle.runtime_flavor() != RuntimeFlavor::CurrentThread || !clock_is_paused() {
            return None;
        }
        let timeline = Self {
            inner: Arc::new(Inner {
                sleepers: Mutex::new(BTreeMap::new()),
                next_id: AtomicU64::new(0),
                registered: Notify::new(),
                origin: Instant::now(),
            }),
        };
        let driver = handle.spawn(drive(Arc::clone(&timeline.inner)));
        Some(TimelineGuard { timeline, driver })
    }

    /// Whether two handles are the same timeline.
    pub(super) fn same_as(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.inner, &other.inner)
    }

    /// Waits until `deadline` on this timeline.
    pub fn sleep_until(&self, deadline: Instant) -> TimelineSleep {
        TimelineSleep {
            inner: Arc::clone(&self.inner),
            deadline,
            key: None,
        }
    }
}

/// Whether tokio's clock stands still: a paused clock does not move while this thread sleeps.
fn clock_is_paused() -> bool {
    let before = Instant::now();
    std::thread::sleep(Duration::from_micros(20));
    Instant::now() == before
}

/// The future of [`VirtualTimeline::sleep_until`].
#[derive(Debug)]
pub struct TimelineSleep {
    inner: Arc<Inner>,
    deadline: Instant,
    key: Option<(Instant, u64)>,
}

impl std::fmt::Debug for Inner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Timeline").finish_non_exhaustive()
    }
}

impl Future for TimelineSleep {
    type Output = ();

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        let this = &mut *self;
        if Instant::now() >= this.deadline {
            if let Some(key) = this.key.take() {
                this.inner.lock().remove(&key);
            }
            return Poll::Ready(());
        }
        let mut sleepers = this.inner.lock();
        match this.key {
            Some(key) => {
                sleepers.insert(key, cx.waker().clone());
            }
            None => {
                let key = (
                    this.deadline,
                    this.inner.next_id.fetch_add(1, Ordering::Relaxed),
                );
                sleepers.insert(key, cx.waker().clone());
                this.key = Some(key);
                drop(sleepers);
                this.inner.registered.notify_one();
            }
        }
        Poll::Pending
    }
}

impl Drop for TimelineSleep {
    fn drop(&mut self) {
        if let Some(key) = self.key.take() {
            self.inner.lock().remove(&key);
        }
    }
}

/// The first millisecond boundary after `now`, counted from `origin`, and whether `now` is
/// itself on one.
fn next_boundary(origin: Instant, now: Instant) -> (Instant, bool) {
    let since = now.saturating_duration_since(origin).as_nanos();
    let tick = TICK.as_nanos();
    let ticks = since / tick;
    let next = origin + Duration::from_nanos(u64::try_from((ticks + 1) * tick).unwrap_or(u64::MAX));
    (next, since.is_multiple_of(tick))
}

/// The driver: let the instant's work run, wake the sleepers due, move the clock.
async fn drive(inner: Arc<Inner>) {
    loop {
        for _ in 0..SETTLE_ROUNDS {
            tokio::task::yield_now().await;
        }
        let now = Instant::now();
        let next = {
            let mut sleepers = inner.lock();
            let mut woke = false;
            while let Some(entry) = sleepers.first_entry() {
                if entry.key().0 > now {
                    break;
                }
                entry.remove().wake();
                woke = true;
            }
            if woke {
                // Let the woken run at this instant before time moves on.
                continue;
            }
            sleepers.keys().next().map(|(deadline, _)| *deadline)
        };
        let (boundary, aligned) = next_boundary(inner.origin, now);
        let target = match next {
            Some(deadline) => deadline.min(boundary),
            None if !aligned => boundary,
            None => {
                // Nothing finer than tokio's timer is waiting and the clock stands on a
                // boundary: let the runtime advance to its next timer as it would without us.
                inner.registered.notified().await;
                continue;
            }
        };
        tokio::time::advance(target.saturating_duration_since(now)).await;
    }
}
