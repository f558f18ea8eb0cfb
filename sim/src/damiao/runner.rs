//! Several Damiao motors on one bus: the task that feeds them frames, steps them every
//! millisecond and sends their replies after the firmware's turnaround; and the handle the
//! harness holds. The same pattern as the RobStride runner (`crate::can_runner`'s step clock,
//! receive tasks and transmit backlog, a supervised task), so it runs under a paused tokio
//! clock in virtual time. With a state file, every save or zero a motor takes is written to it
//! at once ([`crate::damiao::state_file`]), and a file that cannot be written stops the runner.

use std::path::PathBuf;
use std::sync::Arc;

use bus::{CanBus, CanFrame};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::actuator::{ActuatorFirmware, ActuatorSnapshot};
use crate::can_runner::{receive_frames, StepClock, TxBacklog};
use crate::damiao::faults::TEMPERATURE_MAX_C;
use crate::damiao::firmware::{DamiaoMotor, MotorConfig, TURNAROUND};
use crate::damiao::model::Model;
use crate::damiao::state_file::{motor_key, StateFile};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::piper::faults::Shown;
use crate::state_file::{InvalidField, StateFileError};
use crate::supervise::{DeathWatch, Supervisor};

/// Coldest temperature the side door sets (°C): the coldest rating of industrial electronics.
const TEMPERATURE_MIN_C: f64 = -40.0;

/// Configuration of an emulated Damiao bus.
#[derive(Debug, Clone, PartialEq)]
pub struct DamiaoConfig {
    /// The motors, one per ESC_ID.
    pub motors: Vec<MotorConfig>,
    /// Where each motor's flash (its saved registers, ids and zero) lives across restarts,
    /// keyed by its configured ESC_ID ([`crate::damiao::state_file`]); `None` keeps nothing.
    pub state_file: Option<PathBuf>,
}

impl DamiaoConfig {
    /// These motors on one bus, no state file.
    pub fn new(motors: Vec<MotorConfig>) -> Self {
        Self {
            motors,
            state_file: None,
        }
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
    /// The state file puts two motors on one ESC_ID at power-on (a host moved one there and
    /// saved): both would answer every frame for it, and no host could move one away again.
    #[error(
        "the motors configured on ESC_IDs {} and {} would both answer on ESC_ID 0x{esc_id:03X}: \
         the state file {} keeps {} there (a host's write of ESC_ID, then a save). To fix it, \
         edit the file: set `registers.ESC_ID` of that entry to a free ESC_ID, or delete the \
         entry (the motor's saved registers and zero go with it)",
        configured[0], configured[1], state_file.display(), kept.join(" and ")
    )]
    KeptIdClash {
        /// The ESC_ID both would answer on.
        esc_id: u16,
        /// The two motors' configured ESC_IDs, in configuration order.
        configured: [u16; 2],
        /// The entries of the file that moved them (`motors.1`).
        kept: Vec<String>,
        /// The state file.
        state_file: PathBuf,
    },
    /// The state file could not be read or written, or keeps an image a motor refuses.
    #[error(transparent)]
    StateFile(#[from] StateFileError),
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
    /// The request channel to the runner, shared with the monitors it hands out.
    view: DamiaoMonitor,
    task: Option<JoinHandle<()>>,
    death: DeathWatch,
}

/// A shared view of running motors, from [`DamiaoHandle::monitor`]: faults, snapshots and
/// the motors' power-on ids, shareable between tasks (the web view of `armhil sim damiao
/// --ui` holds one). Its calls fail with [`DamiaoError::Stopped`] once the motors are shut
/// down. Front ends reach its faults through [`crate::fault_desk::FaultTarget`]
/// (`crate::damiao::target`).
#[derive(Debug, Clone)]
pub struct DamiaoMonitor {
    requests: mpsc::UnboundedSender<Request>,
    /// The ESC_IDs the motors powered on with, in configuration order.
    esc_ids: Arc<[u16]>,
    /// The MST_IDs they powered on with, in the same order.
    mst_ids: Arc<[u16]>,
    /// Their models, in the same order.
    models: Arc<[Model]>,
}

impl DamiaoBus {
    /// Power on the motors and start answering on `bus` (spawns on the current runtime;
    /// works under a paused clock). Each motor drives its configured rig. A state file from an
    /// earlier run is applied first: a motor it keeps an image for powers on from it (at the
    /// ids a host gave it), and one that would put two motors on one ESC_ID is refused.
    pub fn spawn(config: DamiaoConfig, bus: Arc<dyn CanBus>) -> Result<DamiaoHandle, DamiaoError> {
        for (index, motor) in config.motors.iter().enumerate() {
            motor
                .validate()
                .map_err(|source| DamiaoError::InvalidMotor { index, source })?;
        }
        // The configured ESC_IDs name the motors in the state file: two on one would share an
        // entry, whatever the file says.
        let configured: Vec<u16> = config.motors.iter().map(|m| m.esc_id).collect();
        if let (Some(esc_id), Some(_)) = (first_repeat(&configured), &config.state_file) {
            return Err(DamiaoError::DuplicateEscId { esc_id });
        }
        let (state, powered) = match &config.state_file {
            Some(path) => {
                let state = StateFile::load(path)?;
                let powered = config
                    .motors
                    .iter()
                    .map(|m| {
                        state
                            .power_on(m)
                            .map_err(|invalid| StateFileError::invalid(path, invalid))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                (state, powered)
            }
            None => (StateFile::default(), config.motors.clone()),
        };
        let motors: Vec<DamiaoMotor> = powered.into_iter().map(DamiaoMotor::new).collect();
        // The ids the motors power on with (a flash image may have moved one).
        let esc_ids: Vec<u16> = motors.iter().map(DamiaoMotor::esc_id).collect();
        if let Some(esc_id) = first_repeat(&esc_ids) {
            let on: Vec<usize> = (0..esc_ids.len())
                .filter(|&k| esc_ids[k] == esc_id)
                .collect();
            let pair = [configured[on[0]], configured[on[1]]];
            let kept: Vec<String> = pair
                .iter()
                .filter(|&&c| c != esc_id && state.keeps(c))
                .map(|&c| format!("`motors.{}`", motor_key(c)))
                .collect();
            return Err(match (&config.state_file, kept.is_empty()) {
                (Some(path), false) => DamiaoError::KeptIdClash {
                    esc_id,
                    configured: pair,
                    kept,
                    state_file: path.clone(),
                },
                _ => DamiaoError::DuplicateEscId { esc_id },
            });
        }
        let mst_ids: Vec<u16> = motors.iter().map(DamiaoMotor::mst_id).collect();
        let flash = motors.iter().map(ActuatorFirmware::persisted).collect();
        let (requests, inbox) = mpsc::unbounded_channel();
        let models: Vec<Model> = config.motors.iter().map(|m| m.model).collect();
        let runner = Runner {
            bus,
            backlog: TxBacklog::default(),
            motors,
            flash,
            keys: configured,
            state,
            state_path: config.state_file,
            quiet_steps: 0,
        };
        // A panic or a state file that cannot be written ends the runner; the watch says so.
        let (supervisor, death) = Supervisor::new();
        let task = supervisor.spawn(
            &tokio::runtime::Handle::current(),
            "Damiao runner",
            runner.run(inbox),
        );
        Ok(DamiaoHandle {
            view: DamiaoMonitor {
                requests,
                esc_ids: esc_ids.into(),
                mst_ids: mst_ids.into(),
                models: models.into(),
            },
            task: Some(task),
            death,
        })
    }
}

/// The first value `ids` holds twice, if any.
fn first_repeat(ids: &[u16]) -> Option<u16> {
    ids.iter()
        .enumerate()
        .find(|(k, id)| ids[..*k].contains(id))
        .map(|(_, id)| *id)
}

impl DamiaoHandle {
    async fn ask<T>(
        &self,
        make: impl FnOnce(oneshot::Sender<T>) -> Request,
    ) -> Result<T, DamiaoError> {
        self.view.ask(make).await
    }

    /// Inject the fault `name` (see [`crate::damiao::faults`]) into the motor on `esc_id`: its
    /// cause is set and the error latched; the motor stops.
    pub async fn inject(
        &self,
        esc_id: u16,
        name: &str,
        args: &FaultArgs,
    ) -> Result<(), DamiaoError> {
        self.view.inject(esc_id, name, args).await
    }

    /// Remove fault `name`'s cause; the latch stays until the host's `FB`.
    pub async fn clear(
        &self,
        esc_id: u16,
        name: &str,
        args: &FaultArgs,
    ) -> Result<(), DamiaoError> {
        self.view.clear(esc_id, name, args).await
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
        self.view.snapshot().await
    }

    /// Every motor's flash image (its last save and zero, as
    /// [`ActuatorFirmware::persisted`] writes it), in configuration order: what a restart
    /// passes to [`MotorConfig::from_persisted`].
    pub async fn flash(&self) -> Result<Vec<serde_json::Value>, DamiaoError> {
        self.ask(Request::Flash).await
    }

    /// The ESC_IDs the motors powered on with, in configuration order: a state file's where
    /// it kept one (a host moved the motor in an earlier run), else the configured ones.
    pub fn power_on_ids(&self) -> &[u16] {
        self.view.power_on_ids()
    }

    /// The MST_IDs (feedback ids) the motors powered on with, in configuration order.
    pub fn power_on_mst_ids(&self) -> &[u16] {
        self.view.power_on_mst_ids()
    }

    /// A cloneable view of the motors for monitors (the web view): faults and snapshots.
    pub fn monitor(&self) -> DamiaoMonitor {
        self.view.clone()
    }

    /// A watch that tells when the emulator stops serving on its own (its task panicked, or
    /// its state file could not be written).
    pub fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Stop the motors ("power off"); what they saved is already on disk.
    pub async fn shutdown(mut self) {
        let _ = self.ask(Request::Shutdown).await;
        if let Some(task) = self.task.take() {
            let _ = task.await;
        }
    }
}

impl DamiaoMonitor {
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

    /// See [`DamiaoHandle::inject`].
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

    /// See [`DamiaoHandle::clear`].
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

    /// See [`DamiaoHandle::snapshot`].
    pub async fn snapshot(&self) -> Result<Vec<ActuatorSnapshot>, DamiaoError> {
        self.ask(Request::Snapshot).await
    }

    /// See [`DamiaoHandle::power_on_ids`].
    pub fn power_on_ids(&self) -> &[u16] {
        &self.esc_ids
    }

    /// See [`DamiaoHandle::power_on_mst_ids`].
    pub fn power_on_mst_ids(&self) -> &[u16] {
        &self.mst_ids
    }

    /// The motors' models, in configuration order.
    pub fn models(&self) -> &[Model] {
        &self.models
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
    /// Each motor's configured ESC_ID: its key in the state file.
    keys: Vec<u16>,
    /// What the state file holds (other motors' entries included).
    state: StateFile,
    /// Where it is written, if anywhere.
    state_path: Option<PathBuf>,
    /// Steps in a row in which every motor was disabled.
    quiet_steps: u32,
}

/// Quiet steps after which the clock rests ([`StepClock::rest`]): 0.1 s.
const QUIET_STEPS_BEFORE_REST: u32 = 100;

impl Runner {
    /// Serve until shut down; an `Err` (the state file could not be written) ends it early.
    async fn run(mut self, mut inbox: mpsc::UnboundedReceiver<Request>) -> Result<(), String> {
        let (mut frames, receivers) =
            receive_frames(vec![(Arc::clone(&self.bus), "bus".to_owned())], "damiao");
        // 1 ms steps; a late wake-up runs every step owed (up to the catch-up limit).
        let mut clock = StepClock::start("damiao-clock");
        let outcome = loop {
            tokio::select! {
                biased;
                request = inbox.recv() => match request {
                    Some(Request::Shutdown(done)) => {
                        let _ = done.send(());
                        break Ok(());
                    }
                    Some(request) => {
                        self.catch_up(&mut clock).await;
                        self.serve(request);
                        // A fault or push may change what the next steps do.
                        self.wake(&mut clock);
                    }
                    None => break Ok(()),
                },
                frame = frames.recv() => match frame {
                    Some((_, frame)) => {
                        self.catch_up(&mut clock).await;
                        // A motor told to keep something that cannot be kept: stop, rather
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
                        tracing::debug!(dropped = steps.dropped, "damiao emulator: steps dropped behind the wall clock");
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

    async fn on_frame(&mut self, frame: &CanFrame) -> Result<(), StateFileError> {
        let mut replies = Vec::new();
        let mut changed = false;
        for ((motor, flash), key) in self.motors.iter_mut().zip(&mut self.flash).zip(&self.keys) {
            replies.extend(motor.handle_frame(frame));
            if motor.take_persist_request() {
                *flash = motor.persisted();
                self.state.keep(*key, flash.clone());
                changed = true;
            }
        }
        if let (true, Some(path)) = (changed, &self.state_path) {
            self.state.save(path)?;
        }
        // Answered from the latest step's state, after the firmware's turnaround.
        self.send_after(replies, TURNAROUND).await;
        Ok(())
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

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};

    use super::*;
    use crate::damiao::codec::{register_payload, RegisterCmd};
    use crate::damiao::registers::rid;

    fn register(esc: u16, cmd: RegisterCmd, rid: u8, value: [u8; 4]) -> CanFrame {
        CanFrame::standard(0x7FF, &register_payload(esc, cmd.byte(), rid, value)).unwrap()
    }

    fn spawn(bus: &VirtualBus, config: DamiaoConfig) -> Result<DamiaoHandle, DamiaoError> {
        DamiaoBus::spawn(config, Arc::new(bus.attach("emulator")))
    }

    /// A host moves motor 1 to ESC_ID 5 and saves: the file keeps it under its configured
    /// ESC_ID, and the next run powers it on at 5 (the other motor where it was).
    #[tokio::test(start_paused = true)]
    async fn a_save_is_written_at_once_and_the_next_run_powers_on_from_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("dm.json");
        let mut config = DamiaoConfig::new(vec![
            MotorConfig::new(1, Model::DM4310),
            MotorConfig::new(2, Model::DM4340),
        ]);
        config.state_file = Some(path.clone());
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let host = bus.attach("host");
        let first = spawn(&bus, config.clone()).unwrap();
        host.send(register(
            1,
            RegisterCmd::Write,
            rid::ESC_ID,
            5u32.to_le_bytes(),
        ))
        .await
        .unwrap();
        host.send(register(5, RegisterCmd::Save, 0, [0; 4]))
            .await
            .unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
        assert!(path.exists(), "the save was not written at once");
        first.shutdown().await;
        let kept = StateFile::load(&path).unwrap();
        assert_eq!(kept.motors.keys().collect::<Vec<_>>(), ["1"]);

        let second = spawn(&bus, config.clone()).unwrap();
        assert_eq!(second.power_on_ids(), [5, 2]);
        assert_eq!(second.power_on_mst_ids(), [0x11, 0x12]);
        assert_eq!(second.monitor().models(), [Model::DM4310, Model::DM4340]);
        second.shutdown().await;

        // A third motor configured on 5 would now share it with the moved one.
        config.motors.push(MotorConfig::new(5, Model::DM8009));
        let clash = spawn(&bus, config).unwrap_err().to_string();
        assert!(
            clash.contains("ESC_IDs 1 and 5 would both answer on ESC_ID 0x005")
                && clash.contains("`motors.1`")
                && clash.contains("dm.json"),
            "{clash}"
        );
    }

    /// A save that cannot be written ends the runner: the death watch says why.
    #[tokio::test(start_paused = true)]
    async fn a_state_file_that_cannot_be_written_stops_the_emulator() {
        let dir = tempfile::tempdir().unwrap();
        let mut config = DamiaoConfig::new(vec![MotorConfig::new(1, Model::DM4310)]);
        config.state_file = Some(dir.path().join("gone").join("dm.json"));
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let host = bus.attach("host");
        let emulator = spawn(&bus, config).unwrap();
        let mut death = emulator.death_watch();
        host.send(register(1, RegisterCmd::Save, 0, [0; 4]))
            .await
            .unwrap();
        let died = tokio::time::timeout(Duration::from_secs(1), death.died())
            .await
            .expect("the emulator stops");
        assert!(died.to_string().contains("gone"), "{died}");
    }
}
