//! Link health: frame counters, per-id rates and the monitor task.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Weak;
use std::time::Duration;

use tokio::time::{interval, Instant, MissedTickBehavior};

use super::{lock, Inner};
use crate::piper::state::LinkHealth;

/// Monitor tick: `is_ok` in snapshots is at most this stale.
const TICK: Duration = Duration::from_millis(10);
/// Rates are recomputed every this many ticks …
const RATE_EVERY_TICKS: u32 = 10;
/// … over a window of this many rate samples (1 s).
const RATE_WINDOW: usize = 10;

/// Cumulative frame counts per 11-bit id.
pub(crate) struct Counters {
    per_id: Box<[u64; 0x800]>,
    total: u64,
}

impl Default for Counters {
    fn default() -> Self {
        Self {
            per_id: Box::new([0; 0x800]),
            total: 0,
        }
    }
}

impl Counters {
    /// Count one frame; returns the running total (the frame's sequence number).
    pub(crate) fn count(&mut self, raw_id: u32) -> u64 {
        self.total += 1;
        if let Some(slot) = self.per_id.get_mut(raw_id as usize) {
            *slot += 1;
        }
        self.total
    }

    fn snapshot(&self) -> (u64, BTreeMap<u16, u64>) {
        let ids = self
            .per_id
            .iter()
            .enumerate()
            .filter(|(_, count)| **count > 0)
            .map(|(id, count)| (id as u16, *count))
            .collect();
        (self.total, ids)
    }
}

pub(crate) fn is_fresh(link: &LinkHealth, timeout: Duration) -> bool {
    link.bus_fault.is_none() && link.last_feedback.is_some_and(|at| at.elapsed() <= timeout)
}

/// Publish `ok` every tick and the rates every 100 ms.
pub(crate) async fn monitor_task(weak: Weak<Inner>) {
    let mut ticker = interval(TICK);
    ticker.set_missed_tick_behavior(MissedTickBehavior::Delay);
    let mut history: VecDeque<(Instant, u64, BTreeMap<u16, u64>)> = VecDeque::new();
    let mut ticks = 0u32;
    loop {
        ticker.tick().await;
        let Some(inner) = weak.upgrade() else { return };
        let timeout = inner.config.timeouts.link;
        ticks += 1;
        let rates = if ticks.is_multiple_of(RATE_EVERY_TICKS) {
            let now = Instant::now();
            let (total, ids) = lock(&inner.counters).snapshot();
            history.push_back((now, total, ids));
            while history.len() > RATE_WINDOW + 1 {
                history.pop_front();
            }
            compute_rates(&history)
        } else {
            None
        };
        inner.state.send_if_modified(|s| {
            let ok = is_fresh(&s.link, timeout);
            let mut changed = ok != s.link.ok;
            if ok != s.link.ok {
                tracing::info!(ok, "piper link health changed");
            }
            s.link.ok = ok;
            if let Some((fps, per_id, total)) = &rates {
                s.link.frames_total = *total;
                s.link.frames_per_s = *fps;
                s.link.rates_hz = per_id.clone();
                changed = true;
            }
            changed
        });
    }
}

type Rates = (f64, BTreeMap<u16, f64>, u64);

fn compute_rates(history: &VecDeque<(Instant, u64, BTreeMap<u16, u64>)>) -> Option<Rates> {
    let (first_at, first_total, first_ids) = history.front()?;
    let (last_at, last_total, last_ids) = history.back()?;
    let span = last_at.duration_since(*first_at).as_secs_f64();
    if span <= 0.0 {
        return Some((0.0, BTreeMap::new(), *last_total));
    }
    let per_id = last_ids
        .iter()
        .map(|(id, count)| {
            let before = first_ids.get(id).copied().unwrap_or(0);
            (*id, (count - before) as f64 / span)
        })
        .collect();
    Some((
        (last_total - first_total) as f64 / span,
        per_id,
        *last_total,
    ))
}
