//! Many actuators on one bus: the task that feeds them frames, steps them every millisecond,
//! and sends what they answer; plus the handle the harness holds.

use std::path::PathBuf;
use std::sync::Arc;

use bus::{CanBus, CanFrame};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;

use crate::can_runner::{receive_frames, StepClock, TxBacklog};
use crate::robstride::faults::{
    check_bus_voltage_v, check_external_torque_nm, check_temperature_c, Fault, ValueError,
};
use crate::robstride::firmware::{
    Actuator, MotorConfig, MotorSnapshot, DEFAULT_HOST_ID, TURNAROUND,
};
use crate::robstride::state_file::{uid_key, IdClash, StateFile, StateFileError};
use crate::supervise::{DeathWatch, Supervisor};

/// Configuration of an emulated RobStride bus.
#[derive(Debug, Clone, PartialEq)]
pub struct RobstrideConfig {
    /// The motors, one per CAN ID.
    pub motors: Vec<MotorConfig>,
    /// Host ID the motors answer to until a host speaks (default [`DEFAULT_HOST_ID`]).
    pub host_id: u8,
    /// Where saved parameters, CAN IDs, zeros and pending baud/protocol switches live across
    /// restarts; `None` keeps nothing.
    pub state_file: Option<PathBuf>,
    /// The bus's bit rate: a motor switched to another baud rate goes deaf after a restart.
    pub bus_bitrate_bps: u32,
}

impl RobstrideConfig {
    /// Motors on a 1 Mbit/s bus, host [`DEFAULT_HOST_ID`], no state file.
    pub fn new(motors: Vec<MotorConfig>) -> Self {
        Self {
            motors,
            host_id: DEFAULT_HOST_ID,
            state_file: None,
            bus_bitrate_bps: 1_000_000,
        }
    }
}

/// Why the emulator could not start or a harness request failed.
#[derive(Debug, thiserror::Error)]
pub enum RobstrideError {
    /// Two motors are configured with the same CAN ID.
    #[error("two motors use CAN ID {can_id}")]
    DuplicateCanId {
        /// The ID.
        can_id: u8,
    },
    /// The state file would put two motors on one CAN ID at power-on (a host moved one).
    #[error(transparent)]
    IdClash(Box<IdClash>),
    /// A CAN ID outside 1..=127.
    #[error("CAN ID {can_id} is outside 1..=127")]
    InvalidCanId {
        /// The ID.
        can_id: u8,
    },
    /// No motor answers on this ID.
    #[error("no motor with CAN ID {can_id}")]
    UnknownMotor {
        /// The ID.
        can_id: u8,
    },
    /// The state file could not be read or written.
    #[error(transparent)]
    StateFile(#[from] StateFileError),
    /// A temperature, voltage or external torque that is not finite or out of range
    /// (the bounds and why they are what they are: [`crate::robstride::faults`]).
    #[error("motor {can_id}: {source}")]
    BadValue {
        /// The motor.
        can_id: u8,
        /// What is wrong with the value.
        source: ValueError,
    },
    /// The emulator task has stopped.
    #[error("the RobStride emulator has stopped")]
    Stopped,
}

/// Emulated RobStride actuators on a bus.
#[derive(Debug)]
pub struct RobstrideBus;

enum Request {
    Inject(u8, Fault, oneshot::Sender<Result<(), RobstrideError>>),
    RemoveCause(u8, Fault, oneshot::Sender<Result<(), RobstrideError>>),
    SetVoltage(u8, f64, oneshot::Sender<Result<(), RobstrideError>>),
    SetTemperature(u8, f64, oneshot::Sender<Result<(), RobstrideError>>),
    SetExternalTorque(u8, f64, oneshot::Sender<Result<(), RobstrideError>>),
    Snapshot(oneshot::Sender<Vec<MotorSnapshot>>),
    Shutdown(oneshot::Sender<()>),
}

/// The harness's handle on a running emulator.
#[derive(Debug)]
pub struct RobstrideHandle {
    /// The request channel to the runner, shared with the monitors it hands out.
    view: RobstrideMonitor,
    task: Option<JoinHandle<()>>,
    death: DeathWatch,
}

impl RobstrideBus {
    /// Power on the motors and start answering on `bus` (spawns on the current runtime; works
    /// under a paused clock). A state file from an earlier run is applied first.
    pub fn spawn(
        bus: Arc<dyn CanBus>,
        config: RobstrideConfig,
    ) -> Result<RobstrideHandle, RobstrideError> {
        let state = match &config.state_file {
            Some(path) => StateFile::load(path)?,
            None => StateFile::default(),
        };
        for (k, motor) in config.motors.iter().enumerate() {
            if !(1..=0x7F).contains(&motor.can_id) {
                return Err(RobstrideError::InvalidCanId {
                    can_id: motor.can_id,
                });
            }
            if config.motors[..k].iter().any(|m| m.can_id == motor.can_id) {
                return Err(RobstrideError::DuplicateCanId {
                    can_id: motor.can_id,
                });
            }
        }
        // Motors the state file puts on one ID (a host moved one onto another's) are refused,
        // not served with a warning: both would answer every frame for that ID, so the host
        // could not even move one of them away again (a "set CAN ID" to it moves both), and
        // the harness could reach only the first. Refusing loses nothing: the file is not
        // written before the motors run, and the message says which entry to edit or delete
        // (or the emulator can be started without one of the two and the host move the other).
        // Whatever protocol each speaks and whether it still hears the bus: the harness and
        // the web view address motors by ID alone, and a switch back would make it a clash.
        if let Some(path) = &config.state_file {
            let named = config
                .motors
                .iter()
                .map(|m| (format!("motor {}:{}", m.can_id, m.model.name()), m));
            if let Some(clash) = state.id_clash(path, named) {
                return Err(RobstrideError::IdClash(Box::new(clash)));
            }
        }
        let motors: Vec<Actuator> = config
            .motors
            .iter()
            .map(|motor| {
                let saved = state.saved(motor);
                let mut actuator = Actuator::new(motor.clone(), saved, config.bus_bitrate_bps);
                if saved.is_none() {
                    actuator.set_master_id(config.host_id);
                }
                actuator
            })
            .collect();
        let (requests, inbox) = mpsc::unbounded_channel();
        let configured_ids = motors.iter().map(Actuator::can_id).collect();
        let runner = Runner {
            bus,
            backlog: TxBacklog::default(),
            motors,
            state,
            state_path: config.state_file,
            quiet_steps: 0,
        };
        // A panic or a state file that cannot be written ends the runner; the watch says so.
        let (supervisor, death) = Supervisor::new();
        let task = supervisor.spawn(
            &tokio::runtime::Handle::current(),
            "RobStride runner",
            runner.run(inbox),
        );
        Ok(RobstrideHandle {
            view: RobstrideMonitor {
                requests,
                configured_ids,
            },
            task: Some(task),
            death,
        })
    }
}

impl RobstrideHandle {
    async fn ask<T>(
        &self,
        make: impl FnOnce(oneshot::Sender<T>) -> Request,
    ) -> Result<T, RobstrideError> {
        self.view.ask(make).await
    }

    /// Inject a fault into a motor: its cause is set (heat, supply) or a one-shot event
    /// latched; the motor drops to reset and sends a type-21 frame.
    pub async fn inject(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.view.inject(can_id, fault).await
    }

    /// Remove a fault's cause; the latched bit stays until the host sends stop + clear.
    pub async fn clear(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.view.clear(can_id, fault).await
    }

    /// Set a motor's supply voltage (V).
    pub async fn set_bus_voltage(&self, can_id: u8, volts: f64) -> Result<(), RobstrideError> {
        self.ask(|reply| Request::SetVoltage(can_id, volts, reply))
            .await?
    }

    /// Set a motor's winding temperature (°C).
    pub async fn set_temperature(&self, can_id: u8, celsius: f64) -> Result<(), RobstrideError> {
        self.ask(|reply| Request::SetTemperature(can_id, celsius, reply))
            .await?
    }

    /// Push a motor's load with an external torque (N·m).
    pub async fn set_external_torque(
        &self,
        can_id: u8,
        torque_nm: f64,
    ) -> Result<(), RobstrideError> {
        self.ask(|reply| Request::SetExternalTorque(can_id, torque_nm, reply))
            .await?
    }

    /// Every motor's state, in configuration order.
    pub async fn snapshot(&self) -> Result<Vec<MotorSnapshot>, RobstrideError> {
        self.view.snapshot().await
    }

    /// The CAN ID each motor answered on at power-on, in configuration order: the one the
    /// state file kept for it (a host moved it in an earlier run), else its configured one.
    pub fn power_on_ids(&self) -> &[u8] {
        self.view.configured_ids()
    }

    /// A cloneable view of this emulator for monitors (the web view of `armhil sim --ui`):
    /// snapshot and fault calls, shareable between tasks; they fail with
    /// [`RobstrideError::Stopped`] once the emulator is shut down.
    pub fn monitor(&self) -> RobstrideMonitor {
        self.view.clone()
    }

    /// A watch that tells when the emulator stops serving on its own (its task panicked, or
    /// its state file could not be written); `armhil sim` exits non-zero on it.
    pub fn death_watch(&self) -> DeathWatch {
        self.death.clone()
    }

    /// Stop the emulator (the motors "lose power"); persistent state is already on disk.
    pub async fn shutdown(mut self) {
        let _ = self.ask(Request::Shutdown).await;
        if let Some(task) = self.task.take() {
            let _ = task.await;
        }
    }
}

/// A shared view of a running emulator, from [`RobstrideHandle::monitor`].
#[derive(Debug, Clone)]
pub struct RobstrideMonitor {
    requests: mpsc::UnboundedSender<Request>,
    /// The CAN IDs the motors answered on at power-on (the state file's, else the configured
    /// ones; a host may change them at run time): what a front end suggests as a fault's
    /// `motor`.
    configured_ids: Arc<[u8]>,
}

impl RobstrideMonitor {
    async fn ask<T>(
        &self,
        make: impl FnOnce(oneshot::Sender<T>) -> Request,
    ) -> Result<T, RobstrideError> {
        let (reply, answer) = oneshot::channel();
        self.requests
            .send(make(reply))
            .map_err(|_| RobstrideError::Stopped)?;
        answer.await.map_err(|_| RobstrideError::Stopped)
    }

    /// See [`RobstrideHandle::inject`].
    pub async fn inject(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.ask(|reply| Request::Inject(can_id, fault, reply))
            .await?
    }

    /// See [`RobstrideHandle::clear`].
    pub async fn clear(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.ask(|reply| Request::RemoveCause(can_id, fault, reply))
            .await?
    }

    /// See [`RobstrideHandle::snapshot`].
    pub async fn snapshot(&self) -> Result<Vec<MotorSnapshot>, RobstrideError> {
        self.ask(Request::Snapshot).await
    }

    /// The CAN IDs the motors answered on at power-on, in configuration order: a state
    /// file's where it kept one (a host moved the motor in an earlier run), else the
    /// configured ones.
    pub fn configured_ids(&self) -> &[u8] {
        &self.configured_ids
    }
}

impl Drop for RobstrideHandle {
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
    motors: Vec<Actuator>,
    state: StateFile,
    state_path: Option<PathBuf>,
    /// Steps in a row in which no motor sent or could send anything of its own.
    quiet_steps: u32,
}

/// Quiet steps after which the clock rests ([`StepClock::rest`]): 0.1 s.
const QUIET_STEPS_BEFORE_REST: u32 = 100;

impl Runner {
    /// Serve until shut down; an `Err` (the state file could not be written) ends it early.
    async fn run(mut self, mut inbox: mpsc::UnboundedReceiver<Request>) -> Result<(), String> {
        let (mut frames, receivers) =
            receive_frames(vec![(Arc::clone(&self.bus), "bus".to_owned())], "robstride");
        // 1 ms control steps; the pacer (absolute deadlines in real time) only prompts them.
        // Every step the clock owes runs, so a late wake-up catches up as the firmware's own
        // clock would, up to MAX_CATCH_UP_STEPS (a stalled machine drops the rest).
        let mut clock = StepClock::start("robstride-clock");
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
                        let side_door = !matches!(request, Request::Snapshot(_));
                        self.serve(request).await;
                        if side_door {
                            // A fault, a supply or a temperature may make the next step send.
                            self.wake(&mut clock);
                        }
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
                        tracing::debug!(dropped = steps.dropped, "robstride emulator: steps dropped behind the wall clock");
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
            let sent = self.on_tick().await;
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

    /// Every motor's steps send nothing of their own for now.
    fn quiet(&self) -> bool {
        self.motors.iter().all(Actuator::sends_nothing_on_its_own)
    }

    /// Back to a step every 1 ms.
    fn wake(&mut self, clock: &mut StepClock) {
        self.quiet_steps = 0;
        clock.rest(false);
    }

    fn motor_mut(&mut self, can_id: u8) -> Result<&mut Actuator, RobstrideError> {
        self.motors
            .iter_mut()
            .find(|motor| motor.can_id() == can_id)
            .ok_or(RobstrideError::UnknownMotor { can_id })
    }

    async fn serve(&mut self, request: Request) {
        match request {
            Request::Inject(can_id, fault, reply) => {
                let frame = self.motor_mut(can_id).map(|motor| motor.inject(fault));
                let result = match frame {
                    Ok(frame) => {
                        self.send_all(frame).await;
                        Ok(())
                    }
                    Err(error) => Err(error),
                };
                let _ = reply.send(result);
            }
            Request::RemoveCause(can_id, fault, reply) => {
                let result = self
                    .motor_mut(can_id)
                    .map(|motor| motor.remove_cause(fault));
                let _ = reply.send(result);
            }
            // Every value is range-checked here, where each request reaches its motor: a
            // physically absurd one (1e308 N·m) is refused instead of turning the physics
            // into NaN that the wire would carry as zeros.
            Request::SetVoltage(can_id, volts, reply) => {
                let result = self.motor_mut(can_id).and_then(|motor| {
                    let volts = check_bus_voltage_v(volts)
                        .map_err(|source| RobstrideError::BadValue { can_id, source })?;
                    motor.set_bus_voltage(volts);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::SetTemperature(can_id, celsius, reply) => {
                let result = self.motor_mut(can_id).and_then(|motor| {
                    let celsius = check_temperature_c(celsius)
                        .map_err(|source| RobstrideError::BadValue { can_id, source })?;
                    motor.set_temperature(celsius);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::SetExternalTorque(can_id, torque, reply) => {
                let result = self.motor_mut(can_id).and_then(|motor| {
                    let torque = check_external_torque_nm(motor.config().model, torque)
                        .map_err(|source| RobstrideError::BadValue { can_id, source })?;
                    motor.set_external_torque(torque);
                    Ok(())
                });
                let _ = reply.send(result);
            }
            Request::Snapshot(reply) => {
                let _ = reply.send(self.motors.iter().map(Actuator::snapshot).collect());
            }
            Request::Shutdown(done) => {
                let _ = done.send(());
            }
        }
    }

    async fn on_frame(&mut self, frame: &CanFrame) -> Result<(), StateFileError> {
        let mut replies = Vec::new();
        for motor in &mut self.motors {
            replies.extend(motor.handle_frame(frame));
        }
        self.persist_if_requested()?;
        // Answered with the state of the latest control step, after the firmware's
        // turnaround — not at the next step.
        self.send_after(replies, TURNAROUND).await;
        Ok(())
    }

    /// One step of every motor; whether any sent a frame.
    async fn on_tick(&mut self) -> bool {
        let mut out = Vec::new();
        for motor in &mut self.motors {
            out.extend(motor.tick());
        }
        let sent = !out.is_empty();
        self.send_all(out).await;
        sent
    }

    fn persist_if_requested(&mut self) -> Result<(), StateFileError> {
        let mut changed = false;
        for motor in &mut self.motors {
            if motor.take_persist_request() {
                self.state
                    .motors
                    .insert(uid_key(motor.uid()), motor.persisted());
                changed = true;
            }
        }
        if let (true, Some(path)) = (changed, &self.state_path) {
            self.state.save(path)?;
        }
        Ok(())
    }

    async fn send_all(&mut self, frames: impl IntoIterator<Item = CanFrame>) {
        self.send_after(frames, std::time::Duration::ZERO).await;
    }

    /// Hands `frames` to the bus to leave `delay` from now (a firmware's turnaround).
    async fn send_after(
        &mut self,
        frames: impl IntoIterator<Item = CanFrame>,
        delay: std::time::Duration,
    ) {
        self.backlog
            .send_after(self.bus.as_ref(), frames, delay, "robstride", "bus")
            .await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robstride::{Load, Model};
    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};

    #[tokio::test(start_paused = true)]
    async fn absurd_values_are_refused_and_the_state_stays_finite() {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
        let mut motor = MotorConfig::new(1, Model::RS03);
        motor.load = Load::Pendulum {
            mass_kg: 1.0,
            length_m: 0.3,
        };
        let emulator = RobstrideBus::spawn(node, RobstrideConfig::new(vec![motor])).unwrap();
        let torque = emulator.set_external_torque(1, 1e308).await.unwrap_err();
        assert_eq!(
            torque.to_string(),
            "motor 1: `torque_nm` must be between -600 and 600, got 1e308"
        );
        assert!(emulator.set_temperature(1, 1e308).await.is_err());
        assert!(emulator.set_temperature(1, f64::NAN).await.is_err());
        assert!(emulator.set_bus_voltage(1, -5.0).await.is_err());
        // In range: accepted.
        emulator.set_external_torque(1, 30.0).await.unwrap();
        emulator.set_temperature(1, 60.0).await.unwrap();
        tokio::time::sleep(std::time::Duration::from_millis(200)).await;
        let snapshot = emulator.snapshot().await.unwrap();
        let m = &snapshot[0];
        assert!(
            m.angle_rad.is_finite() && m.speed_rad_s.is_finite() && m.temperature_c.is_finite(),
            "{m:?}"
        );
        emulator.shutdown().await;
    }

    /// Motor 1 moved to motor 2's ID by a host (comm type 7) and the emulator restarted from
    /// its state file: two motors on one ID is refused, naming both, the ID and the file.
    #[tokio::test(start_paused = true)]
    async fn a_state_file_that_puts_two_motors_on_one_id_is_refused_naming_both() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rs.json");
        let mut config = RobstrideConfig::new(vec![
            MotorConfig::new(1, Model::RS03),
            MotorConfig::new(2, Model::RS02),
        ]);
        config.state_file = Some(path.clone());
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let emulator =
            RobstrideBus::spawn(Arc::new(bus.attach("emulator")), config.clone()).unwrap();
        let host = bus.attach("host");
        // Type 7, new ID 2 (bits 23..16), host 0xFD, to motor 1.
        let set_id = CanFrame::extended(0x0702_FD01, &[0; 8]).unwrap();
        host.send(set_id).await.unwrap();
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        let ids: Vec<u8> = emulator
            .snapshot()
            .await
            .unwrap()
            .iter()
            .map(|m| m.can_id)
            .collect();
        assert_eq!(ids, [2, 2]);
        emulator.shutdown().await;

        let error = RobstrideBus::spawn(Arc::new(bus.attach("again")), config)
            .unwrap_err()
            .to_string();
        for part in [
            "motor 1:RS03",
            "motor 2:RS02",
            "CAN ID 2",
            &path.display().to_string(),
        ] {
            assert!(error.contains(part), "{part:?} missing from: {error}");
        }
        let moved = format!(
            "motors.{}",
            uid_key(MotorConfig::new(1, Model::RS03).effective_uid())
        );
        assert!(
            error.contains(&format!("set `{moved}.can_id` to a free ID")),
            "{error}"
        );
    }

    /// A motor a host moved to a free ID comes back there, and the handle says so.
    #[tokio::test(start_paused = true)]
    async fn a_motor_moved_to_a_free_id_powers_on_there() {
        let dir = tempfile::tempdir().unwrap();
        let mut config = RobstrideConfig::new(vec![
            MotorConfig::new(1, Model::RS03),
            MotorConfig::new(2, Model::RS02),
        ]);
        config.state_file = Some(dir.path().join("rs.json"));
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let emulator =
            RobstrideBus::spawn(Arc::new(bus.attach("emulator")), config.clone()).unwrap();
        assert_eq!(emulator.power_on_ids(), [1, 2]);
        let host = bus.attach("host");
        // Type 7: motor 1 → ID 3.
        let set_id = CanFrame::extended(0x0703_FD01, &[0; 8]).unwrap();
        host.send(set_id).await.unwrap();
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        emulator.shutdown().await;
        let again = RobstrideBus::spawn(Arc::new(bus.attach("again")), config).unwrap();
        assert_eq!(again.power_on_ids(), [3, 2]);
        again.shutdown().await;
    }
}
