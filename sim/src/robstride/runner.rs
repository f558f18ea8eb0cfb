//! Many actuators on one bus, served by the shared runner (`crate::actuator::bus_runner`:
//! frames in, 1 ms steps, replies after the turnaround, the state file written at each
//! save): here what is RobStride's own, its configuration's checks, its state file's keys and
//! ID clashes, its side doors (typed faults, supply, temperature, push) and the handle the
//! harness holds. A CAN FD frame reaches no motor (a classic CAN controller).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bus::CanBus;

use crate::actuator::bus_runner::{self, BusKind, BusMonitor, BusTask};
use crate::robstride::faults::{
    check_bus_voltage_v, check_external_torque_nm, check_temperature_c, Fault, ValueError,
};
use crate::robstride::firmware::{Actuator, MotorConfig, MotorSnapshot, DEFAULT_HOST_ID};
use crate::robstride::state_file::{uid_key, IdClash, StateFile, StateFileError};
use crate::supervise::DeathWatch;

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

/// The harness's handle on a running emulator.
#[derive(Debug)]
pub struct RobstrideHandle {
    /// The runner's requests, shared with the monitors it hands out.
    view: RobstrideMonitor,
    /// The runner's task: dropping the handle stops it.
    task: BusTask<Flash>,
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
        let configured_ids = motors.iter().map(Actuator::can_id).collect();
        let (task, bus) = bus_runner::spawn(bus, motors, Flash { state }, config.state_file);
        Ok(RobstrideHandle {
            view: RobstrideMonitor {
                bus,
                configured_ids,
            },
            task,
        })
    }
}

/// The motors' flash as the shared runner keeps it: the state file, an entry per motor's uid.
struct Flash {
    state: StateFile,
}

impl BusKind for Flash {
    type Firmware = Actuator;
    type Id = u8;
    type Error = RobstrideError;
    const LABEL: &'static str = "robstride";
    const TASK: &'static str = "RobStride runner";

    fn stopped() -> RobstrideError {
        RobstrideError::Stopped
    }

    fn unknown(can_id: u8) -> RobstrideError {
        RobstrideError::UnknownMotor { can_id }
    }

    fn keep(&mut self, _index: usize, motor: &Actuator) {
        self.state
            .motors
            .insert(uid_key(motor.uid()), motor.persisted());
    }

    fn save(&self, path: &Path) -> Result<(), StateFileError> {
        self.state.save(path)
    }
}

impl RobstrideHandle {
    /// Inject a fault into a motor: its cause is set (heat, supply) or a one-shot event
    /// latched; the motor drops to reset and sends a type-21 frame.
    pub async fn inject(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.view.inject(can_id, fault).await
    }

    /// Remove a fault's cause; the latched bit stays until the host sends stop + clear.
    pub async fn clear(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.view.clear(can_id, fault).await
    }

    // Every value is range-checked where the request reaches its motor: a physically absurd
    // one (1e308 N·m) is refused instead of turning the physics into NaN that the wire would
    // carry as zeros.

    /// Set a motor's supply voltage (V).
    pub async fn set_bus_voltage(&self, can_id: u8, volts: f64) -> Result<(), RobstrideError> {
        self.view
            .set(can_id, move |motor| {
                motor.set_bus_voltage(check_bus_voltage_v(volts)?);
                Ok(())
            })
            .await
    }

    /// Set a motor's winding temperature (°C).
    pub async fn set_temperature(&self, can_id: u8, celsius: f64) -> Result<(), RobstrideError> {
        self.view
            .set(can_id, move |motor| {
                motor.set_temperature(check_temperature_c(celsius)?);
                Ok(())
            })
            .await
    }

    /// Push a motor's load with an external torque (N·m).
    pub async fn set_external_torque(
        &self,
        can_id: u8,
        torque_nm: f64,
    ) -> Result<(), RobstrideError> {
        self.view
            .set(can_id, move |motor| {
                let model = motor.config().model;
                motor.set_external_torque(check_external_torque_nm(model, torque_nm)?);
                Ok(())
            })
            .await
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
        self.task.death_watch()
    }

    /// Stop the emulator (the motors "lose power"); persistent state is already on disk.
    pub async fn shutdown(self) {
        self.task.shutdown().await;
    }
}

/// A shared view of a running emulator, from [`RobstrideHandle::monitor`].
#[derive(Debug, Clone)]
pub struct RobstrideMonitor {
    /// The runner's requests.
    bus: BusMonitor<Flash>,
    /// The CAN IDs the motors answered on at power-on (the state file's, else the configured
    /// ones; a host may change them at run time): what a front end suggests as a fault's
    /// `motor`.
    configured_ids: Arc<[u8]>,
}

impl RobstrideMonitor {
    /// See [`RobstrideHandle::inject`].
    pub async fn inject(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.bus
            .side_door(can_id, move |motor| {
                Ok(motor.inject(fault).into_iter().collect())
            })
            .await
    }

    /// See [`RobstrideHandle::clear`].
    pub async fn clear(&self, can_id: u8, fault: Fault) -> Result<(), RobstrideError> {
        self.bus
            .side_door(can_id, move |motor| {
                motor.remove_cause(fault);
                Ok(Vec::new())
            })
            .await
    }

    /// See [`RobstrideHandle::snapshot`].
    pub async fn snapshot(&self) -> Result<Vec<MotorSnapshot>, RobstrideError> {
        self.bus
            .read(|motors| motors.iter().map(Actuator::snapshot).collect())
            .await
    }

    /// The CAN IDs the motors answered on at power-on, in configuration order: a state
    /// file's where it kept one (a host moved the motor in an earlier run), else the
    /// configured ones.
    pub fn configured_ids(&self) -> &[u8] {
        &self.configured_ids
    }

    /// Sets a value on the motor on `can_id` with `set`, whose range check's refusal is the
    /// motor's [`RobstrideError::BadValue`].
    async fn set(
        &self,
        can_id: u8,
        set: impl FnOnce(&mut Actuator) -> Result<(), ValueError> + Send + 'static,
    ) -> Result<(), RobstrideError> {
        self.bus
            .side_door(can_id, move |motor| {
                set(motor).map_err(|source| RobstrideError::BadValue { can_id, source })?;
                Ok(Vec::new())
            })
            .await
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robstride::{Load, Model};
    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
    use bus::CanFrame;

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
