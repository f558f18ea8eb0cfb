//! The async emulator: the firmware core on its own tokio tasks, attached to a [`CanBus`].
//!
//! Three tasks: a receiver that queues incoming frames, the 1 kHz core (drains the queue,
//! runs [`Firmware::tick`]) and a transmitter that sends the produced frames in order, retrying
//! while the bus's transmit queue is full. All timing uses `tokio::time`, so the emulator runs
//! in virtual time under a paused clock and in real time on a multi-thread runtime.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use bus::{BusError, CanBus, CanFrame};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::{interval, sleep, MissedTickBehavior};

use super::config::{PiperConfig, PiperError};
use super::faults::{FaultError, PiperFault};
use super::firmware::{Firmware, STEP_S};
use super::state::PiperSimState;
use crate::physics::{ObstacleId, ObstacleShape};

/// Wait between two attempts to queue a frame on a full transmit queue (about one frame time
/// at 1 Mbit/s).
const TX_RETRY_WAIT: Duration = Duration::from_micros(120);
/// Attempts before a frame is dropped (≈ 12 ms of a blocked bus).
const TX_RETRIES: u32 = 100;

/// Starts Piper emulators. See [`PiperEmulator::spawn`].
#[derive(Debug, Clone, Copy)]
pub struct PiperEmulator;

/// A running emulator. Dropping it stops the emulator's tasks; [`PiperHandle::shutdown`] also
/// waits for them.
#[derive(Debug)]
pub struct PiperHandle {
    core: Arc<Mutex<Firmware>>,
    stop: watch::Sender<bool>,
    tasks: Vec<JoinHandle<()>>,
}

impl std::fmt::Debug for Firmware {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Firmware")
            .field("profile", &self.profile())
            .field("time_s", &self.time_s())
            .finish()
    }
}

fn lock(core: &Mutex<Firmware>) -> MutexGuard<'_, Firmware> {
    // A panic inside a tick would poison the lock; the state is still the best we have.
    core.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
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
        let firmware = Firmware::new(config)?;
        tracing::info!(firmware = %firmware.profile(), bus = bus.name(), "Piper emulator starting");
        let core = Arc::new(Mutex::new(firmware));
        let (in_tx, mut in_rx) = mpsc::unbounded_channel::<CanFrame>();
        let (out_tx, mut out_rx) = mpsc::unbounded_channel::<CanFrame>();
        let (stop, stop_rx) = watch::channel(false);

        let rx_bus = Arc::clone(&bus);
        let mut rx_stop = stop_rx.clone();
        let receiver = runtime.spawn(async move {
            loop {
                tokio::select! {
                    biased;
                    r = rx_bus.recv() => match r {
                        Ok(rf) => {
                            if in_tx.send(rf.frame).is_err() {
                                break;
                            }
                        }
                        Err(BusError::Closed) => break,
                        Err(e) => {
                            tracing::warn!(error = %e, "Piper emulator receive error");
                            sleep(Duration::from_millis(1)).await;
                        }
                    },
                    _ = rx_stop.changed() => break,
                }
            }
        });

        let tick_core = Arc::clone(&core);
        let mut tick_stop = stop_rx.clone();
        let ticker = runtime.spawn(async move {
            let mut clock = interval(Duration::from_secs_f64(STEP_S * f64::from(ticks_per_wake)));
            // Under a paused clock no tick is ever late. In real time a stalled process skips
            // the missed steps instead of bursting a backlog of feedback onto the bus.
            clock.set_missed_tick_behavior(MissedTickBehavior::Skip);
            let mut produced = Vec::with_capacity(32);
            loop {
                tokio::select! {
                    biased;
                    _ = clock.tick() => {}
                    _ = tick_stop.changed() => break,
                }
                {
                    let mut fw = lock(&tick_core);
                    while let Ok(frame) = in_rx.try_recv() {
                        fw.handle_frame(&frame);
                    }
                    for _ in 0..ticks_per_wake {
                        fw.tick();
                    }
                    fw.drain_output_into(&mut produced);
                }
                for frame in produced.drain(..) {
                    if out_tx.send(frame).is_err() {
                        return;
                    }
                }
            }
        });

        let tx_bus = bus;
        let mut tx_stop = stop_rx;
        let transmitter = runtime.spawn(async move {
            let mut dropped: u64 = 0;
            loop {
                let frame = tokio::select! {
                    biased;
                    f = out_rx.recv() => match f {
                        Some(f) => f,
                        None => break,
                    },
                    _ = tx_stop.changed() => break,
                };
                let mut attempts = 0;
                loop {
                    match tx_bus.send(frame).await {
                        Ok(()) => break,
                        Err(BusError::Closed) => return,
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
        });

        Ok(PiperHandle {
            core,
            stop,
            tasks: vec![receiver, ticker, transmitter],
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

    /// Stop the emulator and wait for its tasks. It sends nothing afterwards.
    pub async fn shutdown(mut self) {
        let _ = self.stop.send(true);
        for task in self.tasks.drain(..) {
            let _ = task.await;
        }
    }
}

impl Drop for PiperHandle {
    fn drop(&mut self) {
        let _ = self.stop.send(true);
    }
}
