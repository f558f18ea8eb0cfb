//! The emulator's three tasks: the receiver, the 1 kHz core and the transmitter.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bus::{BusError, CanBus, CanFrame, ReceivedFrame};
use tokio::sync::{mpsc, watch};
use tokio::time::{sleep, Instant};

use super::{lock, plan_wake_within, OVERRUN_REPORT_PERIOD, TX_RETRIES, TX_RETRY_WAIT};
use crate::cpu_budget::CpuBudget;
use crate::pacer::Pacer;
use crate::piper::firmware::{Firmware, STEP_S, TURNAROUND};
use crate::realtime::RealtimeCounters;

/// Frames received and not yet handled by the core; a full queue holds the receiver back, and
/// the bus's own receive queue then decides what is dropped (as a CAN controller's FIFO
/// overflows), instead of memory growing under a flood.
pub(super) const RX_QUEUE_FRAMES: usize = crate::can_runner::RX_QUEUE_FRAMES;

/// The receiver task: the bus's frames into the core's queue until stopped or closed.
pub(super) async fn receive(
    bus: Arc<dyn CanBus>,
    in_tx: mpsc::Sender<ReceivedFrame>,
    mut stop: watch::Receiver<bool>,
) -> Result<(), String> {
    loop {
        tokio::select! {
            biased;
            r = bus.recv() => match r {
                Ok(rf) => {
                    if in_tx.send(rf).await.is_err() {
                        break;
                    }
                }
                Err(BusError::Closed) => break,
                Err(e) => {
                    tracing::warn!(error = %e, "Piper emulator receive error");
                    sleep(Duration::from_millis(1)).await;
                }
            },
            _ = stop.changed() => break,
        }
    }
    Ok(())
}

/// What the core task steps and where it counts.
pub(super) struct CoreTask {
    pub(super) core: Arc<Mutex<Firmware>>,
    pub(super) counters: Arc<Mutex<RealtimeCounters>>,
    pub(super) ticks_per_wake: u32,
    pub(super) max_catch_up: u64,
}

/// The core task: at each wake-up, the frames received, then the steps due, then the frames
/// produced to the transmitter.
pub(super) async fn run_core(
    task: CoreTask,
    mut in_rx: mpsc::Receiver<ReceivedFrame>,
    out_tx: mpsc::UnboundedSender<Outgoing>,
    mut stop: watch::Receiver<bool>,
) -> Result<(), String> {
    let CoreTask {
        core,
        counters,
        ticks_per_wake,
        max_catch_up,
    } = task;
    let per_wake = u64::from(ticks_per_wake);
    // The pacer only prompts the wake-ups (on absolute deadlines in real time); how many steps
    // run comes from the clock (`plan_wake_within`), so a skipped wake-up loses no emulated
    // time.
    // The clock's origin first: the pacer's wake-ups then come just after each step's
    // instant, never just before, so the count of steps due does not flip between two
    // wake-ups by timer jitter (which lost one 200 Hz period in ten).
    let boot = Instant::now();
    let mut clock = Pacer::new(
        Duration::from_secs_f64(STEP_S * per_wake as f64),
        "piper-clock",
    );
    let mut done: u64 = 0;
    let mut produced = Vec::with_capacity(32);
    let mut budget = CpuBudget::default();
    let mut last_wake = boot;
    let mut overruns = OverrunReport::default();
    let mut receiving = true;
    loop {
        let arrived = tokio::select! {
            biased;
            _ = clock.tick() => None,
            frame = in_rx.recv(), if receiving => {
                receiving = frame.is_some();
                frame
            }
            _ = stop.changed() => break,
        };
        if let Some(mut latest) = arrived {
            // A frame is handled when it arrives and a query answered after the firmware's
            // turnaround, with the state of the latest step — not at the next step.
            {
                let mut fw = lock(&core);
                fw.handle_frame(&latest.frame);
                while let Ok(frame) = in_rx.try_recv() {
                    fw.handle_frame(&frame.frame);
                    latest = frame;
                }
                fw.drain_output_into(&mut produced);
                if let Some(e) = fw.take_save_error() {
                    return Err(e.to_string());
                }
            }
            for frame in produced.drain(..) {
                if out_tx.send((frame, Some(latest))).is_err() {
                    return Ok(());
                }
            }
            continue;
        }
        let woke = Instant::now();
        // On a machine too slow for real time, catching up a backlog would take the CPU from
        // the clients; the budget lets the emulator fall behind instead.
        let affordable = budget.limit(woke - last_wake, per_wake, max_catch_up);
        last_wake = woke;
        let plan = plan_wake_within(woke - boot, done, per_wake, affordable);
        done += plan.run + plan.skipped;
        let late = plan.run > per_wake;
        {
            let mut fw = lock(&core);
            while let Ok(frame) = in_rx.try_recv() {
                fw.handle_frame(&frame.frame);
            }
            if late {
                fw.catch_up(plan.run as u32);
            } else {
                for _ in 0..plan.run {
                    fw.tick();
                }
            }
            fw.drain_output_into(&mut produced);
            // Parameters a client changed could not be kept: stop serving rather than let the
            // client believe they were stored.
            if let Some(e) = fw.take_save_error() {
                return Err(e.to_string());
            }
        }
        budget.observe(plan.run, woke.elapsed());
        {
            let mut c = lock(&counters);
            c.record_wakeup(woke, plan.run, late);
            if plan.skipped > 0 {
                c.record_overrun(plan.skipped);
                overruns.add(woke, plan.skipped, budget.step_cost());
            } else if late {
                tracing::debug!(steps = plan.run, "Piper emulator caught up a late wake-up");
            }
        }
        for frame in produced.drain(..) {
            if out_tx.send((frame, None)).is_err() {
                // The transmitter ended: on a stop, or because the bus was closed (the owner
                // of the bus closing it first is a way to stop, not a failure).
                return Ok(());
            }
        }
    }
    Ok(())
}

/// Dropped steps, reported at most once per [`OVERRUN_REPORT_PERIOD`]: a machine too slow for
/// real time overruns at every wake-up, and a line per wake-up would flood the log.
#[derive(Default)]
struct OverrunReport {
    unreported_steps: u64,
    last_report: Option<Instant>,
}

impl OverrunReport {
    fn add(&mut self, now: Instant, skipped_steps: u64, step_cost: Option<Duration>) {
        self.unreported_steps += skipped_steps;
        if self
            .last_report
            .is_none_or(|at| now - at >= OVERRUN_REPORT_PERIOD)
        {
            tracing::warn!(
                dropped_steps = self.unreported_steps,
                step_cost_us = step_cost.map(|d| d.as_micros()),
                "Piper emulator behind the wall clock by more than a wake-up may catch up (the \
                 catch-up limit, or the CPU a catch-up may take): steps dropped since the last \
                 report"
            );
            self.unreported_steps = 0;
            self.last_report = Some(now);
        }
    }
}

/// A frame for the transmitter, and for an answer the request it answers: it leaves the
/// firmware's turnaround after the request's last bit, however late the core got round to it.
pub(super) type Outgoing = (CanFrame, Option<ReceivedFrame>);

/// The transmitter task: the core's frames onto the bus (an answer after its turnaround),
/// each retried a few times when the bus's transmit queue is
/// full, then dropped (counted, warned at powers of two).
pub(super) async fn transmit(
    bus: Arc<dyn CanBus>,
    counters: Arc<Mutex<RealtimeCounters>>,
    mut out_rx: mpsc::UnboundedReceiver<Outgoing>,
    mut stop: watch::Receiver<bool>,
) -> Result<(), String> {
    let mut dropped: u64 = 0;
    loop {
        let (frame, request) = tokio::select! {
            biased;
            f = out_rx.recv() => match f {
                Some(f) => f,
                None => break,
            },
            _ = stop.changed() => break,
        };
        let delay = request.map_or(Duration::ZERO, |request| {
            bus.answer_delay(&request, TURNAROUND)
        });
        let mut attempts = 0;
        loop {
            match bus.send_after(frame, delay).await {
                Ok(()) => {
                    lock(&counters).record_frame(frame.raw_id(), Instant::now());
                    break;
                }
                Err(BusError::Closed) => return Ok(()),
                Err(e) => {
                    attempts += 1;
                    if attempts >= TX_RETRIES {
                        dropped += 1;
                        if dropped.is_power_of_two() {
                            tracing::warn!(error = %e, dropped, "Piper emulator dropped a frame");
                        }
                        break;
                    }
                    sleep(TX_RETRY_WAIT).await;
                }
            }
        }
    }
    Ok(())
}
