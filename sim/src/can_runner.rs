//! What the CAN emulators' tasks share (the RobStride motors on one bus, a robot's actuators
//! on several): the 1 ms step clock locked to the wall clock, and the tasks that receive each
//! bus's frames into one bounded queue.

use std::sync::Arc;
use std::time::Duration;

use bus::{BusError, CanBus, CanFrame};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::{sleep, Instant};

/// The actuators' control step.
pub const STEP: Duration = Duration::from_millis(1);
/// Most steps one late wake-up catches up (100 ms of emulated time); a longer stall of the
/// machine is lost time, as for the other emulators.
pub const MAX_CATCH_UP_STEPS: u64 = 100;
/// Frames received from all buses and not yet handled; a full queue holds the receivers
/// back, and each bus's own receive queue then decides what is dropped.
pub const RX_QUEUE_FRAMES: usize = 4096;

/// Counts the steps due since start: steps at 0, 1, 2 … ms, so by elapsed time t,
/// floor(t / 1 ms) + 1 are due. A wake-up is only a prompt: how many steps run comes from the
/// clock, so a late wake-up catches up as the firmware's own clock would.
#[derive(Debug)]
pub struct StepClock {
    started: Instant,
    done: u64,
}

/// What a wake-up runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepsDue {
    /// Steps to run now.
    pub run: u64,
    /// Steps owed beyond [`MAX_CATCH_UP_STEPS`], skipped (the machine stalled).
    pub dropped: u64,
}

impl StepClock {
    /// A clock whose first step is due now.
    pub fn start() -> Self {
        Self {
            started: Instant::now(),
            done: 0,
        }
    }

    /// The steps owed since the last call, counted as done.
    pub fn due(&mut self) -> StepsDue {
        let due = (self.started.elapsed().as_nanos() / STEP.as_nanos()) as u64 + 1;
        let owed = due.saturating_sub(self.done);
        self.done = due;
        let run = owed.min(MAX_CATCH_UP_STEPS);
        StepsDue {
            run,
            dropped: owed - run,
        }
    }
}

/// One task per bus forwarding its frames, tagged with the bus's index in `buses`, into one
/// bounded queue; `label` names the emulator in warnings. Receiving in tasks of their own
/// keeps `recv` out of the runner's `select!` (never cancelled mid-frame). Abort the tasks
/// when the runner ends.
pub fn receive_frames(
    buses: Vec<(Arc<dyn CanBus>, String)>,
    label: &'static str,
) -> (mpsc::Receiver<(usize, CanFrame)>, Vec<JoinHandle<()>>) {
    let (tx, rx) = mpsc::channel(RX_QUEUE_FRAMES);
    let tasks = buses
        .into_iter()
        .enumerate()
        .map(|(index, (bus, name))| {
            let tx = tx.clone();
            tokio::spawn(async move {
                loop {
                    match bus.recv().await {
                        Ok(received) => {
                            if tx.send((index, received.frame)).await.is_err() {
                                break;
                            }
                        }
                        Err(BusError::Closed) => break,
                        Err(error) => {
                            tracing::warn!(emulator = label, bus = %name, %error, "receive error");
                            sleep(Duration::from_millis(1)).await;
                        }
                    }
                }
            })
        })
        .collect();
    (rx, tasks)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn a_late_wake_up_runs_every_step_owed_up_to_the_catch_up_limit() {
        let mut clock = StepClock::start();
        assert_eq!(
            clock.due(),
            StepsDue { run: 1, dropped: 0 },
            "step 0 at once"
        );
        tokio::time::advance(Duration::from_micros(3_500)).await;
        assert_eq!(
            clock.due(),
            StepsDue { run: 3, dropped: 0 },
            "steps 1, 2, 3"
        );
        assert_eq!(
            clock.due(),
            StepsDue { run: 0, dropped: 0 },
            "nothing owed twice"
        );
        tokio::time::advance(Duration::from_millis(250)).await;
        assert_eq!(
            clock.due(),
            StepsDue {
                run: MAX_CATCH_UP_STEPS,
                dropped: 250 - MAX_CATCH_UP_STEPS
            },
            "a stall beyond 100 ms is lost time"
        );
    }
}
