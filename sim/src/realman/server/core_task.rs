//! The 1 kHz core task: physics steps on the clock, controller events routed to their
//! clients, and the UDP realtime push.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use tokio::time::Instant;

use super::connection::route_events;
use super::{lock, Shared, MAX_CATCH_UP_TICKS, OVERRUN_SLACK_MS};
use crate::pacer::Pacer;
use crate::realman::params::PushConfig;
use crate::realman::push::{self, Datagram, PushSink, PushStats};

/// The 1 kHz core: physics steps locked to the (virtual or wall) clock, events routed, and the
/// push sent every `cycle` × 5 ms. After a late wake-up the missed steps run at once and their
/// push periods are coalesced into one datagram.
pub(super) async fn core_loop(shared: Arc<Shared>, sink: PushSink, ticks_per_wake: u64) {
    let mut stop = shared.stop.clone();
    let start = Instant::now();
    // Wake-ups on absolute deadlines in real time (see `Pacer`); the first one, at once,
    // finds nothing due.
    let mut pacer = Pacer::new(Duration::from_millis(ticks_per_wake), "realman-clock");
    let mut done: u64 = 0;
    let mut push_stats = PushStats::default();
    loop {
        tokio::select! {
            _ = pacer.tick() => {}
            _ = stop.changed() => break,
        }
        let due = (Instant::now() - start).as_millis() as u64;
        let behind = due.saturating_sub(done);
        if behind > ticks_per_wake + OVERRUN_SLACK_MS {
            lock(&shared.stats).overruns += 1;
        }
        let run = behind.min(MAX_CATCH_UP_TICKS);
        let mut push_due = false;
        {
            let mut core = lock(&shared.core);
            let cycle_ms = u64::from(core.params().push.cycle.max(1)) * 5;
            for _ in 0..run {
                core.tick();
                done += 1;
                push_due |= done.is_multiple_of(cycle_ms);
            }
        }
        // Skip what could not be caught up rather than bursting it later.
        done = done.max(due.saturating_sub(MAX_CATCH_UP_TICKS));
        route_events(&shared);
        if push_due {
            send_push(&shared, &sink, &mut push_stats).await;
        }
    }
}

/// Where the push goes now (see [`push::targets`]): the one answer the push task and the
/// monitor (the web view) share, so a view never lists an address the push has stopped
/// going to.
pub(super) fn push_targets(shared: &Shared, push: &PushConfig) -> Vec<SocketAddr> {
    if !push.enable {
        return Vec::new();
    }
    let clients: Vec<SocketAddr> = lock(&shared.clients).values().map(|c| c.peer).collect();
    push::targets(&push.ip, push.port, &clients, shared.public)
}

async fn send_push(shared: &Shared, sink: &PushSink, stats: &mut PushStats) {
    let (payload, push) = {
        let core = lock(&shared.core);
        let push = core.params().push.clone();
        if !push.enable {
            return;
        }
        (core.push_datagram(), push)
    };
    for to in push_targets(shared, &push) {
        let out = lock(&shared.push_faults).apply(Datagram {
            to,
            payload: payload.clone(),
        });
        for datagram in out {
            sink.send(datagram, stats).await;
        }
    }
    lock(&shared.stats).push = *stats;
}
