//! What the CAN emulators' tasks share (the RobStride motors on one bus, a robot's actuators
//! on several): the 1 ms step clock locked to the wall clock, and the tasks that receive each
//! bus's frames into one bounded queue, and the transmit backlog that keeps a saturated bus
//! from stopping the clock.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use bus::{BusError, CanBus, CanFrame, ReceivedFrame};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::{sleep, Instant};

use crate::pacer::{Pacer, PacerKind};

/// The actuators' control step.
pub const STEP: Duration = Duration::from_millis(1);
/// Most steps one late wake-up catches up (100 ms of emulated time); a longer stall of the
/// machine is lost time, as for the other emulators.
pub const MAX_CATCH_UP_STEPS: u64 = 100;
/// Steps between two wake-ups of a resting clock ([`StepClock::rest`]): 20 ms.
pub const RESTING_STRIDE_STEPS: u32 = 20;
/// Frames received from all buses and not yet handled; a full queue holds the receivers
/// back, and each bus's own receive queue then decides what is dropped.
pub const RX_QUEUE_FRAMES: usize = 4096;

/// Counts the steps due since start: steps at 0, 1, 2 … ms, so by elapsed time t,
/// floor(t / 1 ms) + 1 are due. A wake-up is only a prompt: how many steps run comes from the
/// clock, so a late wake-up catches up as the firmware's own clock would. The clock owns the
/// [`Pacer`] that prompts it, made after its origin: the wake-ups then come just after each
/// step's instant, never just before, so the count of steps due does not flip between two
/// wake-ups by timer jitter.
#[derive(Debug)]
pub struct StepClock {
    started: Instant,
    done: u64,
    pacer: Pacer,
    /// The pacer thread's name, for the pacers made when the clock rests or wakes.
    name: String,
    /// Whether the pacer wakes every [`RESTING_STRIDE_STEPS`] steps instead of every step.
    resting: bool,
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
    /// A clock whose first step is due now; `name` names its pacer's thread, if it has one.
    pub fn start(name: &str) -> Self {
        let started = Instant::now();
        Self {
            started,
            done: 0,
            pacer: Pacer::new(STEP, name),
            name: name.to_owned(),
            resting: false,
        }
    }

    /// Wakes up every [`RESTING_STRIDE_STEPS`] steps (`true`) or every step again (`false`).
    /// For an emulator whose steps, for now, send nothing of their own: its steps then run in
    /// batches, and it catches them up ([`StepClock::due`]) before it answers a frame or a
    /// request, so a host sees the same answers from the same state, and the machine is woken
    /// fifty times a second instead of a thousand. Under tokio's timer (virtual time, a
    /// current-thread runtime) the clock never rests: runs stay exactly as they were.
    pub fn rest(&mut self, resting: bool) {
        if resting == self.resting || (resting && self.pacer.kind() == PacerKind::TokioTimer) {
            return;
        }
        let period = if resting {
            STEP * RESTING_STRIDE_STEPS
        } else {
            STEP
        };
        self.pacer = Pacer::new(period, &self.name);
        self.resting = resting;
    }

    /// Whether the clock rests ([`StepClock::rest`]).
    pub fn is_resting(&self) -> bool {
        self.resting
    }

    /// Waits for the next wake-up and returns the steps then owed (see [`StepClock::due`]).
    /// Cancel-safe: the wait is, and the count is taken only once it has ended.
    pub async fn next(&mut self) -> StepsDue {
        self.pacer.tick().await;
        self.due()
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
) -> (mpsc::Receiver<(usize, ReceivedFrame)>, Vec<JoinHandle<()>>) {
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
                            if tx.send((index, received)).await.is_err() {
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

/// The emulator's side of a bus's transmit path: frames a bus's full transmit queue refused
/// wait here, lowest CAN identifier first — each actuator on a bus has a controller of its
/// own, so of their waiting frames the one that wins arbitration leaves first, as on the
/// robot — and go to the bus at the next chance (the next frame to send, or the next step).
/// The emulator's loop never waits for the bus: waiting (100 µs at a time, up to 5 ms a
/// frame) let one saturated bus stop every actuator's clock — a robot whose buses were
/// offered 129 % of their bit rate emulated 0.01 s in 4 s of wall time. A real motor's
/// firmware does not wait for its CAN mailboxes either.
///
/// Bounded by what the wire carries: [`TxBacklog::CAPACITY`] frames are well over 100 ms of a
/// saturated 1 Mbit/s bus, so a burst the bus would carry is never dropped (a CANopen node
/// answering 3,000 back-to-back uploads lost 53 answers to the former 64-frame bound); past
/// it the highest identifier is dropped, the frame that would have waited longest.
#[derive(Debug, Default)]
pub struct TxBacklog {
    /// Waiting frames by (arbitration key, arrival number): the order they win the bus.
    frames: BTreeMap<(u64, u64), Waiting>,
    arrivals: u64,
    dropped: u64,
}

/// A frame in the backlog and the earliest instant it may start on the wire.
#[derive(Debug, Clone, Copy)]
struct Waiting {
    frame: CanFrame,
    not_before: Instant,
}

impl TxBacklog {
    /// Frames kept waiting, at most.
    pub const CAPACITY: usize = 1024;

    /// Queue `frames` to leave `delay` from now (a firmware's turnaround; zero for periodic
    /// frames) and hand the bus as many waiting frames as it takes now, lowest identifier
    /// first. `label` and `bus_name` name the emulator and the bus in warnings.
    pub async fn send_after(
        &mut self,
        bus: &dyn CanBus,
        frames: impl IntoIterator<Item = CanFrame>,
        delay: Duration,
        label: &'static str,
        bus_name: &str,
    ) {
        let not_before = Instant::now() + delay;
        for frame in frames {
            let key = (frame.id().arbitration_key(), self.arrivals);
            self.arrivals += 1;
            self.frames.insert(key, Waiting { frame, not_before });
            if self.frames.len() > Self::CAPACITY {
                self.frames.pop_last();
                self.dropped += 1;
                // Warn at 1, 2, 4, 8 … drops: a saturated bus would otherwise log per frame.
                if self.dropped.is_power_of_two() {
                    tracing::warn!(
                        emulator = label,
                        bus = bus_name,
                        dropped = self.dropped,
                        "transmit queue full: frames dropped (the bus carries less than is sent)"
                    );
                }
            }
        }
        while let Some(entry) = self.frames.first_entry() {
            let waiting = *entry.get();
            let delay = waiting.not_before.saturating_duration_since(Instant::now());
            match bus.send_after(waiting.frame, delay).await {
                Ok(()) => {}
                Err(BusError::TxQueueFull { .. }) => return,
                Err(error) => {
                    tracing::debug!(emulator = label, bus = bus_name, %error, frame = %waiting.frame, "frame not sent");
                }
            }
            entry.remove();
        }
    }

    /// [`TxBacklog::send_after`] with no delay.
    pub async fn send(
        &mut self,
        bus: &dyn CanBus,
        frames: impl IntoIterator<Item = CanFrame>,
        label: &'static str,
        bus_name: &str,
    ) {
        self.send_after(bus, frames, Duration::ZERO, label, bus_name)
            .await;
    }

    /// Frames dropped so far because the backlog was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A resting clock wakes every 20 ms with the steps owed since (a loaded machine can only
    /// wake it later, never more often: the bounds hold either way); woken, it no longer rests.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_resting_clock_wakes_every_stride_with_the_steps_owed() {
        let mut clock = StepClock::start("test-clock");
        clock.rest(true);
        assert!(clock.is_resting());
        let started = Instant::now();
        let (mut wakes, mut steps) = (0u32, 0u64);
        while started.elapsed() < Duration::from_millis(200) {
            steps += clock.next().await.run;
            wakes += 1;
        }
        // At most about ten wake-ups (a first one may come at once) for every step owed.
        assert!(wakes <= 13, "{wakes} wake-ups in 200 ms");
        assert!(steps >= 195, "{steps} steps in 200 ms");
        clock.rest(false);
        assert!(!clock.is_resting());
    }

    #[tokio::test(start_paused = true)]
    async fn under_tokio_s_timer_a_clock_never_rests() {
        let mut clock = StepClock::start("test-clock");
        clock.rest(true);
        assert!(!clock.is_resting());
    }

    #[tokio::test(start_paused = true)]
    async fn a_late_wake_up_runs_every_step_owed_up_to_the_catch_up_limit() {
        let mut clock = StepClock::start("test-clock");
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

    /// A bus whose transmit queue holds `room` frames until the test takes them.
    struct Mailbox {
        room: usize,
        sent: std::sync::Mutex<Vec<u8>>,
    }

    impl Mailbox {
        /// A bus whose transmit queue takes `room` frames until its `sent` list is cleared.
        fn with_room(room: usize) -> Self {
            Self {
                room,
                sent: std::sync::Mutex::new(Vec::new()),
            }
        }
    }

    #[async_trait::async_trait]
    impl CanBus for Mailbox {
        async fn send(&self, frame: CanFrame) -> Result<(), BusError> {
            let mut sent = self.sent.lock().unwrap();
            if sent.len() == self.room {
                return Err(BusError::TxQueueFull {
                    capacity: self.room,
                });
            }
            sent.push(frame.data()[0]);
            Ok(())
        }
        async fn recv(&self) -> Result<bus::ReceivedFrame, BusError> {
            Err(BusError::Closed)
        }
        async fn close(&self) {}
        fn name(&self) -> &str {
            "mailbox"
        }
    }

    fn frame(n: u8) -> CanFrame {
        CanFrame::extended(0x0200_01FD, &[n; 8]).unwrap()
    }

    /// A full bus never holds the emulator up: what it refuses waits, in order, for the next
    /// chance, and only the backlog's overflow is lost (the highest identifier, newest first).
    #[tokio::test]
    async fn a_full_bus_defers_frames_in_order_and_never_waits() {
        let bus = Mailbox::with_room(2);
        let mut backlog = TxBacklog::default();
        let started = std::time::Instant::now();
        backlog
            .send(&bus, (0..5).map(frame), "test", "mailbox")
            .await;
        assert_eq!(*bus.sent.lock().unwrap(), [0, 1]);
        // The bus frees its queue; the next step sends the waiting frames first.
        bus.sent.lock().unwrap().clear();
        backlog.send(&bus, [frame(5)], "test", "mailbox").await;
        assert_eq!(*bus.sent.lock().unwrap(), [2, 3]);
        bus.sent.lock().unwrap().clear();
        backlog.send(&bus, [], "test", "mailbox").await;
        assert_eq!(*bus.sent.lock().unwrap(), [4, 5]);
        assert!(started.elapsed() < Duration::from_millis(50), "it waited");
        // A bus that takes nothing: past CAPACITY the frame that would wait longest (the
        // newest of the highest identifier) is the one lost.
        let stuck = Mailbox::with_room(0);
        let mut backlog = TxBacklog::default();
        let flood = (0..TxBacklog::CAPACITY + 10).map(|n| frame((n % 256) as u8));
        backlog.send(&stuck, flood, "test", "stuck").await;
        backlog
            .send(
                &stuck,
                [CanFrame::standard(0x001, &[0xAA]).unwrap()],
                "test",
                "stuck",
            )
            .await;
        assert_eq!(backlog.dropped(), 11);
        let first = backlog.frames.values().next().map(|w| w.frame);
        assert_eq!(
            first.map(|f| f.raw_id()),
            Some(0x001),
            "the urgent frame kept"
        );
    }

    /// Waiting frames leave in arbitration order, the lowest identifier first, whatever
    /// order the firmware produced them in; one identifier keeps its own order.
    #[tokio::test]
    async fn waiting_frames_leave_lowest_identifier_first() {
        let bus = Mailbox::with_room(0);
        let mut backlog = TxBacklog::default();
        let produced = [(0x300, 1), (0x100, 2), (0x200, 3), (0x100, 4)];
        backlog
            .send(
                &bus,
                produced.map(|(id, n)| CanFrame::standard(id, &[n]).unwrap()),
                "test",
                "mailbox",
            )
            .await;
        let order: Vec<u8> = backlog.frames.values().map(|w| w.frame.data()[0]).collect();
        assert_eq!(order, [2, 4, 3, 1]);
    }
}
