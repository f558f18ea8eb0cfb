//! Actuators of one kind on one bus, served by one task: the runner `RobstrideBus` and
//! `DamiaoBus` share. A kind keeps only what is its own ([`BusKind`]: its firmware, its errors,
//! where a save goes in its state file) and checks its configuration before it spawns; the
//! rest is here, over [`ActuatorFirmware`]:
//!
//! - the task feeds every firmware the bus's frames, steps them every millisecond on
//!   [`crate::can_runner`]'s clock (in virtual time under a paused tokio clock) and sends what
//!   they answer through a transmit backlog;
//! - a frame reaches a firmware as its CAN controller takes it ([`super::deliver`]): a CAN FD
//!   frame only one that [`speaks_fd`](ActuatorFirmware::speaks_fd), and the replies leave in
//!   the format the frame came in; they leave after the slowest answering firmware's
//!   turnaround, from the state of the latest step;
//! - while every firmware sends nothing on its own, the clock rests, and the steps owed are
//!   caught up before a frame or a request is served, so the answers are the same;
//! - a persist request is written to the state file at once; a write that fails stops the
//!   runner with its error, which the death watch reports;
//! - the harness's requests are jobs run on the firmwares between steps ([`BusMonitor`]).

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use bus::{CanBus, CanFrame, ReceivedFrame};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use super::{deliver, ActuatorFirmware};
use crate::can_runner::{receive_frames, StepClock, TxBacklog};
use crate::state_file::StateFileError;
use crate::supervise::{DeathWatch, Supervisor};

/// What a kind gives the shared runner: its firmware and how the harness addresses it, its
/// errors, its names in logs, and where what a firmware keeps goes. The value is the state
/// file's image, owned by the runner.
pub(crate) trait BusKind: Send + 'static {
    /// One actuator's firmware.
    type Firmware: ActuatorFirmware + 'static;
    /// The identifier the harness addresses a firmware by (its
    /// [`can_id`](ActuatorFirmware::can_id) now).
    type Id: Copy + Into<u32> + Send + 'static;
    /// The kind's handle's errors.
    type Error: Send + 'static;
    /// The kind in logs and in its clock's thread name (`robstride`).
    const LABEL: &'static str;
    /// The runner's task as a death report names it (`RobStride runner`).
    const TASK: &'static str;
    /// A request to a runner that has stopped.
    fn stopped() -> Self::Error;
    /// A request for a firmware that no one answers as `id`.
    fn unknown(id: Self::Id) -> Self::Error;
    /// Takes what `firmware` (the `index`th configured) keeps into the state file's image,
    /// at its persist request.
    fn keep(&mut self, index: usize, firmware: &Self::Firmware);
    /// Writes the image to `path`.
    fn save(&self, path: &Path) -> Result<(), StateFileError>;
}

/// A harness request run on the firmwares; the frames it returns are sent at once.
type Job<F> = Box<dyn FnOnce(&mut [F]) -> Vec<CanFrame> + Send>;

enum Request<F> {
    /// `wakes`: the job may make the next step send (a fault, a supply, a temperature).
    Job {
        job: Job<F>,
        wakes: bool,
    },
    Shutdown(oneshot::Sender<()>),
}

/// Power on `firmwares` (in configuration order) on `bus` and serve them in a supervised
/// task on the current runtime; `kind` holds the state file's image, written to
/// `state_path` at every persist request.
pub(crate) fn spawn<K: BusKind>(
    bus: Arc<dyn CanBus>,
    firmwares: Vec<K::Firmware>,
    kind: K,
    state_path: Option<PathBuf>,
) -> (BusTask<K>, BusMonitor<K>) {
    let (requests, inbox) = mpsc::unbounded_channel();
    let monitor = BusMonitor { requests };
    let runner = Runner {
        bus,
        backlog: TxBacklog::default(),
        firmwares,
        kind,
        state_path,
        quiet_steps: 0,
    };
    // A panic or a state file that cannot be written ends the runner; the watch says so.
    let (supervisor, death) = Supervisor::new();
    let task = supervisor.spawn(
        &tokio::runtime::Handle::current(),
        K::TASK,
        runner.run(inbox),
    );
    let task = BusTask {
        monitor: monitor.clone(),
        task: Some(task),
        death,
    };
    (task, monitor)
}

/// The runner's task, held by the kind's handle: dropping it stops the firmwares.
pub(crate) struct BusTask<K: BusKind> {
    monitor: BusMonitor<K>,
    task: Option<JoinHandle<()>>,
    death: DeathWatch,
}

impl<K: BusKind> BusTask<K> {
    /// A watch that tells when the runner stops on its own (its task panicked, or its state
    /// file could not be written).
    pub(crate) fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Stops the runner and waits for it (the firmwares "lose power"); what they kept is
    /// already on disk.
    pub(crate) async fn shutdown(mut self) {
        let (done, stopped) = oneshot::channel();
        if self.monitor.requests.send(Request::Shutdown(done)).is_ok() {
            let _ = stopped.await;
        }
        if let Some(task) = self.task.take() {
            let _ = task.await;
        }
    }
}

impl<K: BusKind> Drop for BusTask<K> {
    fn drop(&mut self) {
        if let Some(task) = self.task.take() {
            task.abort();
        }
    }
}

impl<K: BusKind> fmt::Debug for BusTask<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BusTask")
            .field("kind", &K::LABEL)
            .field("death", &self.death)
            .finish_non_exhaustive()
    }
}

/// The request channel to the runner, cloneable and shareable between tasks; its calls fail
/// with [`BusKind::stopped`] once the runner has stopped.
pub(crate) struct BusMonitor<K: BusKind> {
    requests: mpsc::UnboundedSender<Request<K::Firmware>>,
}

impl<K: BusKind> Clone for BusMonitor<K> {
    fn clone(&self) -> Self {
        Self {
            requests: self.requests.clone(),
        }
    }
}

impl<K: BusKind> fmt::Debug for BusMonitor<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BusMonitor")
            .field("kind", &K::LABEL)
            .finish_non_exhaustive()
    }
}

impl<K: BusKind> BusMonitor<K> {
    /// Runs `job` on the firmwares in the runner, after the steps owed, and returns its value;
    /// the frames it returns are sent at once.
    async fn ask<T: Send + 'static>(
        &self,
        wakes: bool,
        job: impl FnOnce(&mut [K::Firmware]) -> (T, Vec<CanFrame>) + Send + 'static,
    ) -> Result<T, K::Error> {
        let (reply, answer) = oneshot::channel();
        let job: Job<K::Firmware> = Box::new(move |firmwares| {
            let (value, frames) = job(firmwares);
            let _ = reply.send(value);
            frames
        });
        self.requests
            .send(Request::Job { job, wakes })
            .map_err(|_| K::stopped())?;
        answer.await.map_err(|_| K::stopped())
    }

    /// What `read` makes of the firmwares (in configuration order), as of the latest step.
    pub(crate) async fn read<T: Send + 'static>(
        &self,
        read: impl FnOnce(&[K::Firmware]) -> T + Send + 'static,
    ) -> Result<T, K::Error> {
        self.ask(false, move |firmwares| (read(firmwares), Vec::new()))
            .await
    }

    /// The bench's side door to the firmware addressed as `id` now: `act` runs on it (a
    /// fault, a supply, a temperature, a push), the frames it returns (a fault report) are
    /// sent at once, and the steps wake, since the next one may send. [`BusKind::unknown`]
    /// when no firmware answers as `id`.
    pub(crate) async fn side_door(
        &self,
        id: K::Id,
        act: impl FnOnce(&mut K::Firmware) -> Result<Vec<CanFrame>, K::Error> + Send + 'static,
    ) -> Result<(), K::Error> {
        self.ask(true, move |firmwares| {
            let addressed = firmwares.iter_mut().find(|f| f.can_id() == id.into());
            match addressed.map(act) {
                Some(Ok(frames)) => (Ok(()), frames),
                Some(Err(error)) => (Err(error), Vec::new()),
                None => (Err(K::unknown(id)), Vec::new()),
            }
        })
        .await?
    }
}

struct Runner<K: BusKind> {
    bus: Arc<dyn CanBus>,
    /// Frames the bus's full transmit queue refused, sent first at the next chance.
    backlog: TxBacklog,
    firmwares: Vec<K::Firmware>,
    /// The kind's state file image.
    kind: K,
    /// Where it is written, if anywhere.
    state_path: Option<PathBuf>,
    /// Steps in a row in which no firmware sent or could send anything of its own.
    quiet_steps: u32,
}

/// Quiet steps after which the clock rests ([`StepClock::rest`]): 0.1 s.
const QUIET_STEPS_BEFORE_REST: u32 = 100;

impl<K: BusKind> Runner<K> {
    /// Serve until shut down; an `Err` (the state file could not be written) ends it early.
    async fn run(
        mut self,
        mut inbox: mpsc::UnboundedReceiver<Request<K::Firmware>>,
    ) -> Result<(), String> {
        let (mut frames, receivers) =
            receive_frames(vec![(Arc::clone(&self.bus), "bus".to_owned())], K::LABEL);
        // 1 ms control steps; the pacer (absolute deadlines in real time) only prompts them.
        // Every step the clock owes runs, so a late wake-up catches up as the firmware's own
        // clock would, up to MAX_CATCH_UP_STEPS (a stalled machine drops the rest).
        let mut clock = StepClock::start(&format!("{}-clock", K::LABEL));
        let outcome = loop {
            tokio::select! {
                biased;
                request = inbox.recv() => match request {
                    Some(Request::Shutdown(done)) => {
                        let _ = done.send(());
                        break Ok(());
                    }
                    Some(Request::Job { job, wakes }) => {
                        self.catch_up(&mut clock).await;
                        let frames = job(&mut self.firmwares);
                        self.send_after(frames, Duration::ZERO).await;
                        if wakes {
                            self.wake(&mut clock);
                        }
                    }
                    None => break Ok(()),
                },
                frame = frames.recv() => match frame {
                    Some((_, frame)) => {
                        self.catch_up(&mut clock).await;
                        // A firmware told to keep something that cannot be kept: stop, rather
                        // than let the host believe it was saved.
                        if let Err(error) = self.on_frame(&frame).await {
                            break Err(error.to_string());
                        }
                        if !self.quiet() {
                            self.wake(&mut clock);
                        }
                    }
                    None => break Ok(()),
                },
                steps = clock.next() => {
                    if steps.dropped > 0 {
                        tracing::debug!(
                            emulator = K::LABEL,
                            dropped = steps.dropped,
                            "steps dropped behind the wall clock"
                        );
                    }
                    self.run_steps(steps.run, &mut clock).await;
                }
            }
        };
        for receiver in receivers {
            receiver.abort();
        }
        outcome
    }

    /// Runs `steps` steps; after enough quiet ones in a row, lets the clock rest.
    async fn run_steps(&mut self, steps: u64, clock: &mut StepClock) {
        for _ in 0..steps {
            let mut out = Vec::new();
            for firmware in &mut self.firmwares {
                out.extend(firmware.tick());
            }
            let sent = !out.is_empty();
            // Also a step without frames of its own sends what a busy bus refused earlier.
            self.send_after(out, Duration::ZERO).await;
            if sent || !self.quiet() {
                self.wake(clock);
            } else {
                self.quiet_steps = self.quiet_steps.saturating_add(1);
            }
        }
        if self.quiet_steps >= QUIET_STEPS_BEFORE_REST {
            clock.rest(true);
        }
    }

    /// A resting clock's steps owed until now, run before a frame or request is handled: the
    /// answer comes from the state of the latest step, as it would without the rest.
    async fn catch_up(&mut self, clock: &mut StepClock) {
        if clock.is_resting() {
            let steps = clock.due();
            self.run_steps(steps.run, clock).await;
        }
    }

    /// Every firmware's steps send nothing of their own for now.
    fn quiet(&self) -> bool {
        self.firmwares
            .iter()
            .all(ActuatorFirmware::sends_nothing_on_its_own)
    }

    /// Back to a step every 1 ms.
    fn wake(&mut self, clock: &mut StepClock) {
        self.quiet_steps = 0;
        clock.rest(false);
    }

    async fn on_frame(&mut self, received: &ReceivedFrame) -> Result<(), StateFileError> {
        let mut replies = Vec::new();
        let mut turnaround = Duration::ZERO;
        for firmware in &mut self.firmwares {
            let answer = deliver(firmware, &received.frame);
            if !answer.is_empty() {
                turnaround = turnaround.max(firmware.turnaround());
            }
            replies.extend(answer);
        }
        self.persist_if_requested()?;
        // Answered with the state of the latest step, after the slowest answering firmware's
        // turnaround — not at the next step — counted from the request's last bit: the time
        // this emulator took to get round to it is part of the turnaround, not added to it.
        let delay = self.bus.answer_delay(received, turnaround);
        self.send_after(replies, delay).await;
        Ok(())
    }

    /// Keeps what each firmware a host told to save keeps, and writes the state file at once.
    fn persist_if_requested(&mut self) -> Result<(), StateFileError> {
        let mut changed = false;
        for (index, firmware) in self.firmwares.iter_mut().enumerate() {
            if firmware.take_persist_request() {
                self.kind.keep(index, firmware);
                changed = true;
            }
        }
        if let (true, Some(path)) = (changed, &self.state_path) {
            self.kind.save(path)?;
        }
        Ok(())
    }

    /// Hands `frames` to the bus to leave `delay` from now (a firmware's turnaround).
    async fn send_after(&mut self, frames: Vec<CanFrame>, delay: Duration) {
        self.backlog
            .send_after(self.bus.as_ref(), frames, delay, K::LABEL, "bus")
            .await;
    }
}
