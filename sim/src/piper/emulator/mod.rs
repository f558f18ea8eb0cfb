//! The async emulator: the firmware core on its own tokio tasks, attached to a [`CanBus`].
//!
//! Three tasks: a receiver that queues incoming frames, the 1 kHz core (drains the queue,
//! runs [`Firmware::tick`]) and a transmitter that sends the produced frames in order, retrying
//! while the bus's transmit queue is full. All timing uses `tokio::time`, so the emulator runs
//! in virtual time under a paused clock and in real time on a multi-thread runtime.
//!
//! Real-time lock: the core counts the 1 ms steps due since boot from the clock, not from its
//! wake-ups. A late wake-up runs every missed step (emulated time keeps up with the wall
//! clock) and sends each periodic feedback frame once for the missed periods, never a backlog
//! burst. A backlog beyond [`MAX_CATCH_UP_STEPS`], or beyond what half a core can run in the
//! time since the previous wake-up at the measured cost of a step
//! ([`CpuBudget`](crate::cpu_budget::CpuBudget)), is dropped and counted as an overrun rather
//! than spun through: on a machine too slow for real time the
//! emulator falls behind instead of starving its clients. Under a paused clock no wake-up is
//! ever late and computing takes no time, so nothing changes there.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use bus::CanBus;
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;

use super::config::{PiperConfig, PiperError};
use super::faults::{FaultError, PiperFault};
use super::firmware::{Firmware, STEP_S};
use super::state::PiperSimState;
use crate::physics::{ObstacleId, ObstacleShape};
use crate::realtime::{RealtimeCounters, RealtimeStats};
use crate::supervise::{DeathWatch, Supervisor};

mod tasks;
use tasks::{receive, run_core, transmit, CoreTask, RX_QUEUE_FRAMES};

/// Wait between two attempts to queue a frame on a full transmit queue (about one frame time
/// at 1 Mbit/s).
const TX_RETRY_WAIT: Duration = Duration::from_micros(120);
/// Attempts before a frame is dropped (≈ 12 ms of a blocked bus).
const TX_RETRIES: u32 = 100;
/// Largest backlog of missed steps a wake-up runs (100 ms of emulated time); beyond it the
/// clock skips ahead so a stalled process does not spin through seconds of physics.
pub const MAX_CATCH_UP_STEPS: u64 = 100;
/// One control step, ns.
const STEP_NS: u128 = (STEP_S * 1e9) as u128;
/// Overruns are logged at most this often (summed in between).
const OVERRUN_REPORT_PERIOD: Duration = Duration::from_secs(1);

/// Starts Piper emulators. See [`PiperEmulator::spawn`].
#[derive(Debug, Clone, Copy)]
pub struct PiperEmulator;

/// A running emulator. Dropping it stops the emulator's tasks; [`PiperHandle::shutdown`] also
/// waits for them.
#[derive(Debug)]
pub struct PiperHandle {
    core: Arc<Mutex<Firmware>>,
    counters: Arc<Mutex<RealtimeCounters>>,
    stop: watch::Sender<bool>,
    tasks: Vec<JoinHandle<()>>,
    death: DeathWatch,
}

impl std::fmt::Debug for Firmware {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Firmware")
            .field("profile", &self.profile())
            .field("time_s", &self.time_s())
            .finish()
    }
}

fn lock<T>(core: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic inside a tick would poison the lock; the state is still the best we have.
    core.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// How many steps a wake-up runs and whether it drops a backlog.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct WakePlan {
    /// Steps to run now.
    run: u64,
    /// Steps dropped (an overrun when non-zero).
    skipped: u64,
}

/// Steps due at a wake-up `elapsed` after boot with `done` steps run so far: everything up to
/// the end of the current wake period, at most [`MAX_CATCH_UP_STEPS`] of it.
#[cfg(test)]
fn plan_wake(elapsed: Duration, done: u64, ticks_per_wake: u64) -> WakePlan {
    plan_wake_within(elapsed, done, ticks_per_wake, MAX_CATCH_UP_STEPS)
}

/// What a wake-up runs: every step due by the end of the current wake period, at most
/// `max_catch_up` of them (at least one wake's worth); the rest are skipped.
fn plan_wake_within(
    elapsed: Duration,
    done: u64,
    ticks_per_wake: u64,
    max_catch_up: u64,
) -> WakePlan {
    let due = (elapsed.as_nanos() / STEP_NS) as u64 + ticks_per_wake;
    let missing = due.saturating_sub(done);
    if missing > max_catch_up.max(ticks_per_wake) {
        WakePlan {
            run: ticks_per_wake,
            skipped: missing - ticks_per_wake,
        }
    } else {
        WakePlan {
            run: missing,
            skipped: 0,
        }
    }
}

impl PiperEmulator {
    /// Boot a Piper on `bus` and spawn its tasks on the current tokio runtime.
    ///
    /// The arm starts as a real one powers on (spec §8.1): standby, joints disabled, feedback
    /// streaming at 200/40 Hz (3040 frames/s). Works on a current-thread runtime with a paused
    /// clock (virtual time) and on a multi-thread runtime (real time).
    pub fn spawn(bus: Arc<dyn CanBus>, config: PiperConfig) -> Result<PiperHandle, PiperError> {
        let runtime = tokio::runtime::Handle::try_current().map_err(|_| PiperError::NoRuntime)?;
        let ticks_per_wake = config.ticks_per_wake.clamp(1, 25);
        let max_catch_up = config.max_catch_up_steps.unwrap_or(MAX_CATCH_UP_STEPS);
        let firmware = Firmware::new(config)?;
        tracing::info!(firmware = %firmware.profile(), bus = bus.name(), "Piper emulator starting");
        let core = Arc::new(Mutex::new(firmware));
        let counters = Arc::new(Mutex::new(RealtimeCounters::new()));
        let (in_tx, in_rx) = mpsc::channel::<bus::ReceivedFrame>(RX_QUEUE_FRAMES);
        let (out_tx, out_rx) = mpsc::unbounded_channel::<tasks::Outgoing>();
        let (stop, stop_rx) = watch::channel(false);
        // A task that panics or gives up is reported, not left dead behind an open bus.
        let (supervisor, death) = Supervisor::new();

        let receiver = supervisor.spawn(
            &runtime,
            "Piper receiver",
            receive(Arc::clone(&bus), in_tx, stop_rx.clone()),
        );
        let ticker = supervisor.spawn(
            &runtime,
            "Piper core",
            run_core(
                CoreTask {
                    core: Arc::clone(&core),
                    counters: Arc::clone(&counters),
                    ticks_per_wake,
                    max_catch_up,
                },
                in_rx,
                out_tx,
                stop_rx.clone(),
            ),
        );
        let transmitter = supervisor.spawn(
            &runtime,
            "Piper transmitter",
            transmit(bus, Arc::clone(&counters), out_rx, stop_rx),
        );

        Ok(PiperHandle {
            core,
            counters,
            stop,
            tasks: vec![receiver, ticker, transmitter],
            death,
        })
    }
}

impl PiperHandle {
    /// Inject a fault (see [`crate::piper::faults`] for how each shows on the wire).
    pub fn inject(&self, fault: PiperFault) -> Result<(), FaultError> {
        lock(&self.core).inject(fault)
    }

    /// Remove a fault's cause (the values in `fault`, such as a temperature, do not matter).
    pub fn clear(&self, fault: PiperFault) -> Result<(), FaultError> {
        lock(&self.core).clear(fault)
    }

    /// Place a static obstacle in the physics world (position of its centre in the base
    /// frame, m). Touching it pushes the arm; with collision protection on, the arm stops.
    pub fn add_obstacle(&self, shape: ObstacleShape, position_m: [f64; 3]) -> ObstacleId {
        lock(&self.core).add_obstacle(shape, position_m)
    }

    /// Remove an obstacle.
    pub fn remove_obstacle(&self, id: ObstacleId) {
        lock(&self.core).remove_obstacle(id);
    }

    /// The simulation's ground truth now.
    pub fn snapshot(&self) -> PiperSimState {
        lock(&self.core).snapshot()
    }

    /// Timing figures since boot: frames and inter-frame periods per ID, late wake-ups and
    /// overruns of the real-time clock.
    pub fn stats(&self) -> RealtimeStats {
        lock(&self.counters).report()
    }

    /// A cloneable view of this emulator for monitors (the web view of `armhil sim --ui`):
    /// the same snapshot, fault and timing calls as the handle, shareable between tasks.
    pub fn monitor(&self) -> PiperMonitor {
        PiperMonitor {
            core: Arc::clone(&self.core),
            counters: Arc::clone(&self.counters),
        }
    }

    /// A watch that tells when the emulator stops serving on its own: a task panicked, or the
    /// state file could not be written. `armhil sim` exits non-zero on it instead of keeping
    /// a dead bus open.
    pub fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Stop the emulator and wait for its tasks. It sends nothing afterwards.
    pub async fn shutdown(mut self) {
        let _ = self.stop.send(true);
        for task in self.tasks.drain(..) {
            let _ = task.await;
        }
    }
}

/// A shared view of a running emulator, from [`PiperHandle::monitor`]. It does not keep the
/// emulator running: after the handle shuts it down, [`PiperMonitor::snapshot`] returns the
/// last state.
#[derive(Debug, Clone)]
pub struct PiperMonitor {
    core: Arc<Mutex<Firmware>>,
    counters: Arc<Mutex<RealtimeCounters>>,
}

impl PiperMonitor {
    /// See [`PiperHandle::inject`].
    pub fn inject(&self, fault: PiperFault) -> Result<(), FaultError> {
        lock(&self.core).inject(fault)
    }

    /// See [`PiperHandle::clear`].
    pub fn clear(&self, fault: PiperFault) -> Result<(), FaultError> {
        lock(&self.core).clear(fault)
    }

    /// See [`PiperHandle::snapshot`].
    pub fn snapshot(&self) -> PiperSimState {
        lock(&self.core).snapshot()
    }

    /// See [`PiperHandle::stats`].
    pub fn stats(&self) -> RealtimeStats {
        lock(&self.counters).report()
    }
}

impl Drop for PiperHandle {
    fn drop(&mut self) {
        let _ = self.stop.send(true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_smaller_catch_up_budget_skips_sooner() {
        // 50 steps behind: within the default budget, beyond a 5-step one.
        let p = plan_wake_within(Duration::from_millis(50), 5, 5, 5);
        assert_eq!((p.run, p.skipped), (5, 45));
        let p = plan_wake_within(Duration::from_millis(50), 5, 5, MAX_CATCH_UP_STEPS);
        assert_eq!((p.run, p.skipped), (50, 0));
    }

    #[test]
    fn an_on_time_wake_runs_one_period() {
        let p = plan_wake(Duration::from_millis(10), 10, 5);
        assert_eq!(p, WakePlan { run: 5, skipped: 0 });
        // The very first wake-up, at boot.
        assert_eq!(
            plan_wake(Duration::ZERO, 0, 1),
            WakePlan { run: 1, skipped: 0 }
        );
    }

    #[test]
    fn a_late_wake_runs_the_missed_steps() {
        // Woke 12.4 ms after boot having run 5 steps: steps up to 12 + one period are due.
        let p = plan_wake(Duration::from_micros(12_400), 5, 5);
        assert_eq!(
            p,
            WakePlan {
                run: 12,
                skipped: 0
            }
        );
    }

    #[test]
    fn a_stall_beyond_the_bound_skips_ahead() {
        let p = plan_wake(Duration::from_millis(500), 100, 5);
        assert_eq!(p.run, 5);
        assert_eq!(p.run + p.skipped, 405);
    }
}

#[cfg(test)]
mod catch_up_tests {
    use super::super::PiperConfig;
    use super::*;
    use bus::CanFrame;

    fn count(frames: &[CanFrame], id: u32) -> usize {
        frames.iter().filter(|f| f.raw_id() == id).count()
    }

    #[test]
    fn catch_up_runs_every_step_but_sends_each_feedback_frame_once() {
        let mut live = Firmware::new(PiperConfig::default()).expect("boots");
        let mut late = Firmware::new(PiperConfig::default()).expect("boots");
        for _ in 0..50 {
            live.tick();
        }
        late.catch_up(50);
        let (live_out, late_out) = (live.take_output(), late.take_output());
        // 50 ms: ten 200 Hz groups and two 40 Hz groups live; one of each caught up.
        assert_eq!(count(&live_out, 0x2A1), 10);
        assert_eq!(count(&live_out, 0x261), 2);
        assert_eq!(count(&late_out, 0x2A1), 1);
        assert_eq!(count(&late_out, 0x261), 1);
        // The physics ran the same 50 steps, and the frame sent is the newest one.
        assert_eq!(live.time_s(), late.time_s());
        let last_live = live_out.iter().rev().find(|f| f.raw_id() == 0x2A5);
        let last_late = late_out.iter().rev().find(|f| f.raw_id() == 0x2A5);
        assert_eq!(last_live, last_late);
    }
}

#[cfg(test)]
mod death_tests {
    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
    use bus::CanFrame;

    use super::super::PiperConfig;
    use super::*;
    use crate::supervise::EmulatorDied;

    #[tokio::test(start_paused = true)]
    async fn a_state_file_that_cannot_be_written_stops_the_emulator_and_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        // D19: the folder is gone by the time a parameter changes.
        let path = dir.path().join("removed").join("piper.json");
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let host = bus.attach("host");
        let config = PiperConfig {
            state_file: Some(path),
            ..PiperConfig::default()
        };
        let emu = PiperEmulator::spawn(Arc::new(bus.attach("piper")), config).unwrap();
        let mut watch = emu.death_watch();
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert_eq!(watch.now(), None, "a running emulator is not dead");
        // 0x47A: collision levels, kept in flash, so the file is written.
        let levels = CanFrame::standard(0x47A, &[3, 3, 3, 3, 3, 3, 0, 0]).unwrap();
        host.send(levels).await.unwrap();
        let died = tokio::time::timeout(Duration::from_secs(1), watch.died())
            .await
            .expect("the failed write stops the emulator");
        assert!(
            matches!(&died, EmulatorDied::Failed { message, .. } if message.contains("piper.json")),
            "{died:?}"
        );
        emu.shutdown().await;
    }

    #[tokio::test(start_paused = true)]
    async fn a_clean_shutdown_is_not_a_death() {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let emu =
            PiperEmulator::spawn(Arc::new(bus.attach("piper")), PiperConfig::default()).unwrap();
        let watch = emu.death_watch();
        tokio::time::sleep(Duration::from_millis(20)).await;
        emu.shutdown().await;
        assert_eq!(watch.now(), None);
    }

    #[test]
    fn a_configured_flash_with_min_above_max_is_refused_at_boot() {
        let mut flash = super::super::Flash::default();
        flash.min_angle_ddeg[1] = 500;
        flash.max_angle_ddeg[1] = 400;
        let config = PiperConfig {
            flash: Some(flash),
            ..PiperConfig::default()
        };
        match Firmware::new(config) {
            Err(e @ super::super::PiperError::InvalidFlash(_)) => {
                assert!(e.to_string().contains("min_angle_ddeg[1]"), "{e}");
            }
            other => panic!("expected a refusal, got {:?}", other.map(|_| ())),
        }
    }
}
