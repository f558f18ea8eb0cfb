//! Several Damiao motors on one bus, served by the shared runner
//! (`crate::actuator::bus_runner`: frames in, 1 ms steps in virtual time under a paused tokio
//! clock, replies after the firmware's turnaround in the format the request came in — a CAN
//! FD request gets CAN FD replies — and a supervised task): here what is Damiao's own, its
//! configuration's checks, its state file's keys ([`crate::damiao::state_file`]: every save or
//! zero a motor takes is written at once, and a file that cannot be written stops the runner),
//! ESC_ID clashes, its side doors and the handle the harness holds.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bus::CanBus;

use crate::actuator::bus_runner::{self, BusKind, BusMonitor, BusTask};
use crate::actuator::{ActuatorFirmware, ActuatorSnapshot};
use crate::damiao::faults::TEMPERATURE_MAX_C;
use crate::damiao::firmware::{DamiaoMotor, MotorConfig};
use crate::damiao::model::Model;
use crate::damiao::state_file::{motor_key, StateFile};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::piper::faults::Shown;
use crate::state_file::{InvalidField, StateFileError};
use crate::supervise::DeathWatch;

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

/// The harness's handle on running motors; dropping it stops them.
#[derive(Debug)]
pub struct DamiaoHandle {
    /// The runner's requests, shared with the monitors it hands out.
    view: DamiaoMonitor,
    /// The runner's task: dropping the handle stops it.
    task: BusTask<Flash>,
}

/// A shared view of running motors, from [`DamiaoHandle::monitor`]: faults, snapshots and
/// the motors' power-on ids, shareable between tasks (the web view of `armhil sim damiao
/// --ui` holds one). Its calls fail with [`DamiaoError::Stopped`] once the motors are shut
/// down. Front ends reach its faults through [`crate::fault_desk::FaultTarget`]
/// (`crate::damiao::target`).
#[derive(Debug, Clone)]
pub struct DamiaoMonitor {
    /// The runner's requests.
    bus: BusMonitor<Flash>,
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
        let models: Vec<Model> = config.motors.iter().map(|m| m.model).collect();
        let flash = Flash {
            state,
            keys: configured,
        };
        let (task, bus) = bus_runner::spawn(bus, motors, flash, config.state_file);
        Ok(DamiaoHandle {
            view: DamiaoMonitor {
                bus,
                esc_ids: esc_ids.into(),
                mst_ids: mst_ids.into(),
                models: models.into(),
            },
            task,
        })
    }
}

/// The motors' flash as the shared runner keeps it: the state file, an entry per motor under
/// its configured ESC_ID.
struct Flash {
    /// What the state file holds (other motors' entries included).
    state: StateFile,
    /// Each motor's configured ESC_ID: its key in the state file.
    keys: Vec<u16>,
}

impl BusKind for Flash {
    type Firmware = DamiaoMotor;
    type Id = u16;
    type Error = DamiaoError;
    const LABEL: &'static str = "damiao";
    const TASK: &'static str = "Damiao runner";

    fn stopped() -> DamiaoError {
        DamiaoError::Stopped
    }

    fn unknown(esc_id: u16) -> DamiaoError {
        DamiaoError::UnknownMotor { esc_id }
    }

    fn keep(&mut self, index: usize, motor: &DamiaoMotor) {
        self.state
            .keep(self.keys[index], ActuatorFirmware::persisted(motor));
    }

    fn save(&self, path: &Path) -> Result<(), StateFileError> {
        self.state.save(path)
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
        self.view
            .bus
            .side_door(esc_id, move |motor| {
                let range = (TEMPERATURE_MIN_C, TEMPERATURE_MAX_C);
                motor.set_coil_temperature(within(esc_id, "temperature_c", celsius, range)?);
                Ok(Vec::new())
            })
            .await
    }

    /// Push a motor's shaft with an external torque (N·m, within ten times its peak).
    pub async fn set_external_torque(
        &self,
        esc_id: u16,
        torque_nm: f64,
    ) -> Result<(), DamiaoError> {
        self.view
            .bus
            .side_door(esc_id, move |motor| {
                let max = motor.max_external_torque_nm();
                motor.push(within(esc_id, "torque_nm", torque_nm, (-max, max))?);
                Ok(Vec::new())
            })
            .await
    }

    /// Every motor's state, in configuration order.
    pub async fn snapshot(&self) -> Result<Vec<ActuatorSnapshot>, DamiaoError> {
        self.view.snapshot().await
    }

    /// Every motor's flash image (its last save and zero, as
    /// [`ActuatorFirmware::persisted`] writes it), in configuration order: what a restart
    /// passes to [`MotorConfig::from_persisted`].
    pub async fn flash(&self) -> Result<Vec<serde_json::Value>, DamiaoError> {
        // A motor's image changes only with a persist request, which the runner writes at
        // once: what it holds now is what it last kept.
        self.view
            .bus
            .read(|motors| motors.iter().map(ActuatorFirmware::persisted).collect())
            .await
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
        self.task.death_watch()
    }

    /// Stop the motors ("power off"); what they saved is already on disk.
    pub async fn shutdown(self) {
        self.task.shutdown().await;
    }
}

impl DamiaoMonitor {
    /// See [`DamiaoHandle::inject`].
    pub async fn inject(
        &self,
        esc_id: u16,
        name: &str,
        args: &FaultArgs,
    ) -> Result<(), DamiaoError> {
        let (name, args) = (name.to_owned(), args.clone());
        self.bus
            .side_door(esc_id, move |motor| {
                ActuatorFirmware::inject(motor, &name, &args)
                    .map_err(|source| DamiaoError::Fault { esc_id, source })
            })
            .await
    }

    /// See [`DamiaoHandle::clear`].
    pub async fn clear(
        &self,
        esc_id: u16,
        name: &str,
        args: &FaultArgs,
    ) -> Result<(), DamiaoError> {
        let (name, args) = (name.to_owned(), args.clone());
        self.bus
            .side_door(esc_id, move |motor| {
                ActuatorFirmware::clear(motor, &name, &args)
                    .map_err(|source| DamiaoError::Fault { esc_id, source })?;
                Ok(Vec::new())
            })
            .await
    }

    /// See [`DamiaoHandle::snapshot`].
    pub async fn snapshot(&self) -> Result<Vec<ActuatorSnapshot>, DamiaoError> {
        self.bus
            .read(|motors| motors.iter().map(ActuatorFirmware::snapshot).collect())
            .await
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
    use bus::CanFrame;

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
