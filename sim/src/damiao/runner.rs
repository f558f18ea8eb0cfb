//! Several Damiao motors on one bus: the task that feeds them frames, steps them every
//! millisecond and sends their replies after the firmware's turnaround; and the handle the
//! harness holds. The same pattern as the RobStride runner (`crate::can_runner`'s step clock,
//! receive tasks and transmit backlog, a supervised task), so it runs under a paused tokio
//! clock in virtual time.

use std::sync::Arc;

use bus::{CanBus, CanFrame};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::actuator::{ActuatorFirmware, ActuatorSnapshot};
use crate::can_runner::{receive_frames, StepClock, TxBacklog};
use crate::damiao::faults::TEMPERATURE_MAX_C;
use crate::damiao::firmware::{DamiaoMotor, MotorConfig, TURNAROUND};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::piper::faults::Shown;
use crate::state_file::InvalidField;
use crate::supervise::{DeathWatch, Supervisor};

/// Coldest temperature the side door sets (°C): the coldest rating of industrial electronics.
const TEMPERATURE_MIN_C: f64 = -40.0;

/// Configuration of an emulated Damiao bus.
#[derive(Debug, Clone, PartialEq)]
pub struct DamiaoConfig {
    /// The motors, one per ESC_ID.
    pub motors: Vec<MotorConfig>,
}

impl DamiaoConfig {
    /// These motors on one bus.
    pub fn new(motors: Vec<MotorConfig>) -> Self {
        Self { motors }
    }
}

/// Why the emulator could not start or a harness request failed.
#[derive(Debug, thiserror::Error)]
pub enum DamiaoError {
    /// A motor's configuration holds a value its firmware would refuse.
    #[error("motor {index}: {source}")]
    InvalidMotor {
        /// Its place in the configuration.
        index: usize,
        /// The field and why.
        source: InvalidField,
    },
    /// Two motors power on with the same ESC_ID (both would answer every frame for it).
    #[error("two motors use ESC_ID 0x{esc_id:03X}")]
    DuplicateEscId {
        /// The id.
        esc_id: u16,
    },
    /// No motor answers on this ESC_ID.
    #[error("no motor with ESC_ID 0x{esc_id:03X}")]
    UnknownMotor {
        /// The id.
        esc_id: u16,
    },
    /// A fault that could not be built (its name or arguments).
    #[error("motor 0x{esc_id:03X}: {source}")]
    Fault {
        /// The motor.
        esc_id: u16,
        /// Why.
        source: FaultArgError,
    },
    /// A temperature or push that is not finite or out of range.
    #[error("motor 0x{esc_id:03X}: `{param}` must be between {} and {}, got {}", Shown(*.min), Shown(*.max), Shown(*.value))]
    BadValue {
        /// The motor.
        esc_id: u16,
        /// The parameter (`temperature_c`, `torque_nm`).
        param: &'static str,
        /// The value given.
        value: f64,
        /// Smallest accepted.
        min: f64,
        /// Largest accepted.
        max: f64,
    },
    /// The emulator task has stopped.
    #[error("the Damiao emulator has stopped")]
    Stopped,
}

/// Emulated Damiao motors on a bus.
#[derive(Debug)]
pub struct DamiaoBus;

type Reply<T> = oneshot::Sender<Result<T, DamiaoError>>;

enum Request {
    Inject(u16, String, FaultArgs, Reply<()>),
    Clear(u16, String, FaultArgs, Reply<()>),
    SetTemperature(u16, f64, Reply<()>),
    SetExternalTorque(u16, f64, Reply<()>),
    Snapshot(oneshot::Sender<Vec<ActuatorSnapshot>>),
    Flash(oneshot::Sender<Vec<serde_json::Value>>),
    Shutdown(oneshot::Sender<()>),
}

/// The harness's handle on running motors; dropping it stops them.
#[derive(Debug)]
pub struct DamiaoHandle {
    requests: mpsc::UnboundedSender<Request>,
    task: Option<JoinHandle<()>>,
    death: DeathWatch,
    esc_ids: Vec<u16>,
}

impl DamiaoBus {
    /// Power on the motors and start answering on `bus` (spawns on the current runtime;
    /// works under a paused clock). Each motor drives its configured rig.
    pub fn spawn(config: DamiaoConfig, bus: Arc<dyn CanBus>) -> Result<DamiaoHandle, DamiaoError> {
        for (index, motor) in config.motors.iter().enumerate() {
            motor
                .validate()
                .map_err(|source| DamiaoError::InvalidMotor { index, source })?;
        }
        let motors: Vec<DamiaoMotor> = config.motors.into_iter().map(DamiaoMotor::new).collect();
        // The ids the motors power on with (a flash image may have moved one).
        let esc_ids: Vec<u16> = motors.iter().map(DamiaoMotor::esc_id).collect();
        for (k, id) in esc_ids.iter().enumerate() {
            if esc_ids[..k].contains(id) {
                return Err(DamiaoError::DuplicateEscId { esc_id: *id });
            }
        }
        let flash = motors.iter().map(ActuatorFirmware::persisted).collect();
        let (requests, inbox) = mpsc::unbounded_channel();
        let runner = Runner {
            bus,
            backlog: TxBacklog::default(),
            motors,
            flash,
            quiet_steps: 0,
        };
        let (supervisor, death) = Supervisor::new();
        let task = supervisor.spawn(
            &tokio::runtime::Handle::current(),
            "Damiao runner",
            runner.run(inbox),
        );
        Ok(DamiaoHandle {
            requests,
            task: Some(task),
            death,
            esc_ids,
        })
    }
}

impl DamiaoHandle {
    async fn ask<T>(
        &self,
        make: impl FnOnce(oneshot::Sender<T>) -> Request,
    ) -> Result<T, DamiaoError> {
        let (reply, answer) = oneshot::channel();
        self.requests
            .send(make(reply))
            .map_err(|_| DamiaoError::Stopped)?;
        answer.await.map_err(|_| DamiaoError::Stopped)
    }

    /// Inject the fault `name` (see [`crate::damiao::faults`]) into the motor on `esc_id`: its
    /// cause is set and the error latched; the motor stops.
    pub async fn inject(
        &self,
        esc_id: u16,
        name: &str,
        args: &FaultArgs,
    ) -> Result<(), DamiaoError> {
        let (name, args) = (name.to_owned(), args.clone());
        self.ask(|reply| Request::Inject(esc_id, name, args, reply))
            .await?
    }

    /// Remove fault `name`'s cause; the latch stays until the host's `FB`.
    pub async fn clear(
        &self,
        esc_id: u16,
        name: &str,
        args: &FaultArgs,
    ) -> Result<(), DamiaoError> {
        let (name, args) = (name.to_owned(), args.clone());
        self.ask(|reply| Request::Clear(esc_id, name, args, reply))
            .await?
    }

    /// Set a motor's coil temperature (°C, −40..=200).
    pub async fn set_temperature(&self, esc_id: u16, celsius: f64) -> Result<(), DamiaoError> {
        self.ask(|reply| Request::SetTemperature(esc_id, celsius, reply))
            .await?
    }

    /// Push a motor's shaft with an external torque (N·m, within ten times its peak).
    pub async fn set_external_torque(
        &self,
        esc_id: u16,
        torque_nm: f64,
    ) -> Result<(), DamiaoError> {
        self.ask(|reply| Request::SetExternalTorque(esc_id, torque_nm, reply))
            .await?
    }

    /// Every motor's state, in configuration order.
    pub async fn snapshot(&self) -> Result<Vec<ActuatorSnapshot>, DamiaoError> {
        self.ask(Request::Snapshot).await
    }

    /// Every motor's flash image (its last save and zero, as
    /// [`ActuatorFirmware::persisted`] writes it), in configuration order: what a restart
    /// passes to [`MotorConfig::from_persisted`].
    pub async fn flash(&self) -> Result<Vec<serde_json::Value>, DamiaoError> {
        self.ask(Request::Flash).await
    }

    /// The ESC_IDs the motors powered on with, in configuration order.
    pub fn power_on_ids(&self) -> &[u16] {
        &self.esc_ids
    }

    /// A watch that tells when the emulator stops serving on its own (its task panicked).
    pub fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Stop the motors ("power off").
    pub async fn shutdown(mut self) {
        let _ = self.ask(Request::Shutdown).await;
        if let Some(task) = self.task.take() {
            let _ = task.await;
        }
    }
}

impl Drop for DamiaoHandle {
    fn drop(&mut self) {
        if let Some(task) = self.task.take() {
            task.abort();
        }
    }
}

struct Runner {
    bus: Arc<dyn CanBus>,
    /// Frames the bus's full transmit queue refused, sent first at the next chance.
    backlog: TxBacklog,
    motors: Vec<DamiaoMotor>,
    /// Each motor's flash image as of its last save or zero.
    flash: Vec<serde_json::Value>,
    /// Steps in a row in which every motor was disabled.
    quiet_steps: u32,
}

/// Quiet steps after which the clock rests ([`StepClock::rest`]): 0.1 s.
const QUIET_STEPS_BEFORE_REST: u32 = 100;

impl Runner {
    async fn run(mut self, mut inbox: mpsc::UnboundedReceiver<Request>) -> Result<(), String> {
        let (mut frames, receivers) =
            receive_frames(vec![(Arc::clone(&self.bus), "bus".to_owned())], "damiao");
        // 1 ms steps; a late wake-up runs every step owed (up to the catch-up limit).
        let mut clock = StepClock::start("damiao-clock");
        loop {
            tokio::select! {
                biased;
                request = inbox.recv() => match request {
                    Some(Request::Shutdown(done)) => {
                        let _ = done.send(());
                        break;
                    }
                    Some(request) => {
                        self.catch_up(&mut clock).await;
                        self.serve(request);
                        // A fault or push may change what the next steps do.
                        self.wake(&mut clock);
                    }
                    None => break,
                },
                frame = frames.recv() => match frame {
                    Some((_, frame)) => {
                        self.catch_up(&mut clock).await;
                        self.on_frame(&frame).await;
                        if !self.quiet() {
                            self.wake(&mut clock);
                        }
                    }
                    None => break,
                },
                steps = clock.next() => {
                    if steps.dropped > 0 {
                        tracing::debug!(dropped = steps.dropped, "damiao emulator: steps dropped behind the wall clock");
                    }
                    self.run_steps(steps.run, &mut clock).await;
                }
            }
        }
        for receiver in receivers {
            receiver.abort();
        }
        Ok(())
    }

    async fn run_steps(&mut self, steps: u64, clock: &mut StepClock) {
        for _ in 0..steps {
            let mut out = Vec::new();
            for motor in &mut self.motors {
                out.extend(motor.tick());
            }
            let sent = !out.is_empty();
            self.send_after(out, std::time::Duration::ZERO).await;
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

    /// A resting clock's owed steps, run before a frame or request is handled: the answer
    /// comes from the latest step's state.
    async fn catch_up(&mut self, clock: &mut StepClock) {
        if clock.is_resting() {
            let steps = clock.due();
            self.run_steps(steps.run, clock).await;
        }
    }

    fn quiet(&self) -> bool {
        self.motors
            .iter()
            .all(ActuatorFirmware::sends_nothing_on_its_own)
    }

    fn wake(&mut self, clock: &mut StepClock) {
        self.quiet_steps = 0;
        clock.rest(false);
    }

    fn motor_mut(&mut self, esc_id: u16) -> Result<&mut DamiaoMotor, DamiaoError> {
        self.motors
            .iter_mut()
            .find(|m| m.esc_id() == esc_id)
            .ok_or(DamiaoError::UnknownMotor { esc_id })
    }

    fn serve(&mut self, request: Request) {
        match request {
            Request::Inject(esc_id, name, args, reply) => {
                let result = self.motor_mut(esc_id).and_then(|motor| {
                    ActuatorFirmware::inject(motor, &name, &args)
                        .map(drop)
                        .map_err(|source| DamiaoError::Fault { esc_id, source })
                });
                let _ = reply.send(result);
            }
            Request::Clear(esc_id, name, args, reply) => {
                let result = self.motor_mut(esc_id).and_then(|motor| {
                    ActuatorFirmware::clear(motor, &name, &args)
                        .map_err(|source| DamiaoError::Fault { esc_id, source })
                });
                let _ = reply.send(result);
            }
            Request::SetTemperature(esc_id, celsius, reply) => {
                let result = self.motor_mut(esc_id).and_then(|motor| {
                    let range = (TEMPERATURE_MIN_C, TEMPERATURE_MAX_C);
                    within(esc_id, "temperature_c", celsius, range)?;
                    motor.set_coil_temperature(celsius);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::SetExternalTorque(esc_id, torque, reply) => {
                let result = self.motor_mut(esc_id).and_then(|motor| {
                    let max = motor.max_external_torque_nm();
                    within(esc_id, "torque_nm", torque, (-max, max))?;
                    motor.push(torque);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::Snapshot(reply) => {
                let _ = reply.send(self.motors.iter().map(ActuatorFirmware::snapshot).collect());
            }
            Request::Flash(reply) => {
                let _ = reply.send(self.flash.clone());
            }
            Request::Shutdown(done) => {
                let _ = done.send(());
            }
        }
    }

    async fn on_frame(&mut self, frame: &CanFrame) {
        let mut replies = Vec::new();
        for (motor, flash) in self.motors.iter_mut().zip(&mut self.flash) {
            replies.extend(motor.handle_frame(frame));
            if motor.take_persist_request() {
                *flash = motor.persisted();
            }
        }
        // Answered from the latest step's state, after the firmware's turnaround.
        self.send_after(replies, TURNAROUND).await;
    }

    async fn send_after(&mut self, frames: Vec<CanFrame>, delay: std::time::Duration) {
        self.backlog
            .send_after(self.bus.as_ref(), frames, delay, "damiao", "bus")
            .await;
    }
}

/// `value` if finite and within `(min, max)`, else the harness's error.
fn within(
    esc_id: u16,
    param: &'static str,
    value: f64,
    (min, max): (f64, f64),
) -> Result<f64, DamiaoError> {
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(DamiaoError::BadValue {
            esc_id,
            param,
            value,
            min,
            max,
        })
    }
}
