//! Damiao motors on the bench: the [`Device`] that drives `driver::damiao` against the
//! in-process `sim::damiao` emulator on the scenario's virtual bus (or a separate emulator
//! process on a real interface).
//!
//! A Damiao motor sends nothing unasked, so the host reads each motor's state every
//! [`DEFAULT_POLL_PERIOD`] with the refresh request, as a host's control loop does (LeRobot's
//! and the OpenArm library's read state each cycle); `do: poll` changes a motor's period or
//! stops its reads (a host gone quiet, which the motor's CAN timeout notices).

mod actions;
#[cfg(test)]
mod tests;

use std::collections::BTreeMap;
use std::future::Future;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use async_trait::async_trait;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use driver::damiao::{DamiaoDriver, DamiaoMotor, DriverConfig};
use sim::actuator::ActuatorSnapshot;
use sim::damiao::{DamiaoBus, DamiaoConfig, DamiaoHandle};

use super::model::{DamiaoSettings, DmFault, MotorCheck};
use super::observe::{MotorObservation, Observation};
use crate::devices::contract::bus_emulator::{BenchEmulator, BusEmulator};
use crate::devices::contract::health::{motors_finite, HealthProbe, MotorPhysics};
use crate::devices::{Action, Check, DeviceFault};
use crate::devices::{Device, DeviceError, Reply, TraceColumn};
use crate::scenario::Signal;

/// How often the host reads each motor's state unless a `poll` step says otherwise.
pub(crate) const DEFAULT_POLL_PERIOD: Duration = Duration::from_millis(10);

/// One motor as the bench knows it: its identifiers and model, in bench order.
#[derive(Debug, Clone, Copy)]
struct MotorIds {
    esc_id: u16,
    mst_id: u16,
    model: driver::damiao::Model,
}

/// The host's reads of one motor: their period (zero: none) and the task making them.
#[derive(Default)]
struct Poll {
    period: Duration,
    task: Option<tokio::task::JoinHandle<()>>,
}

/// A bus of Damiao motors: one driver, one handle per motor, the host's reads, the emulator.
pub(crate) struct DamiaoDevice {
    name: String,
    /// Owns the receive task that feeds every motor handle (dropping it stops the task).
    driver: DamiaoDriver,
    /// The motors, in bench order (the trace's column order).
    ids: Vec<MotorIds>,
    /// The driver's handle on each motor, by ESC_ID.
    motors: Mutex<BTreeMap<u16, Arc<DamiaoMotor>>>,
    /// The host's periodic reads, by ESC_ID.
    polls: Mutex<BTreeMap<u16, Poll>>,
    /// Emulator faults injected and not yet cleared, so `clear_faults` can undo them.
    active: Mutex<Vec<DmFault>>,
    /// The in-process emulator (none on a real interface).
    emulator: BenchEmulator<DamiaoBus>,
    /// The emulator's state, asked for after the last step and read after the next one (see
    /// [`Device::emulator_health`]).
    health: HealthProbe<Vec<ActuatorSnapshot>, sim::damiao::DamiaoError>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A poisoned map of handles is still consistent (inserts and removes are atomic).
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl DamiaoDevice {
    /// Start the emulator (when given a virtual bus) and the driver with a handle per motor,
    /// each read every [`DEFAULT_POLL_PERIOD`].
    pub(crate) fn start(
        name: &str,
        settings: &DamiaoSettings,
        host: Arc<dyn CanBus>,
        emulator_bus: Option<&VirtualBus>,
        timeout: Duration,
    ) -> Result<Self, String> {
        let emulator = BenchEmulator::start(name, "dm", emulator_bus, |state_file| DamiaoConfig {
            motors: settings.motors.clone(),
            state_file: Some(state_file),
        })?;
        let driver = DamiaoDriver::new(
            host,
            DriverConfig {
                timeout,
                ..DriverConfig::default()
            },
        );
        let ids = settings
            .motors
            .iter()
            .map(|m| {
                Ok(MotorIds {
                    esc_id: m.esc_id,
                    mst_id: m.mst_id,
                    model: driver::damiao::Model::parse(m.model.name()).ok_or_else(|| {
                        format!("device `{name}`: driver has no model {}", m.model.name())
                    })?,
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        let device = Self {
            name: name.to_owned(),
            driver,
            ids,
            motors: Mutex::new(BTreeMap::new()),
            polls: Mutex::new(
                settings
                    .motors
                    .iter()
                    .map(|m| {
                        let poll = Poll {
                            period: DEFAULT_POLL_PERIOD,
                            task: None,
                        };
                        (m.esc_id, poll)
                    })
                    .collect(),
            ),
            active: Mutex::new(Vec::new()),
            emulator,
            health: HealthProbe::new(),
        };
        device.open_handles()?;
        Ok(device)
    }

    /// A handle on every motor, and its reads started: at power-on, and after a power cycle
    /// (a fresh host view: what a handle remembered, such as the control mode, is gone).
    fn open_handles(&self) -> Result<(), String> {
        let mut motors = BTreeMap::new();
        for m in &self.ids {
            let motor = self
                .driver
                .motor(m.esc_id, m.mst_id, m.model)
                .map_err(|e| format!("device `{}`: motor {}: {e}", self.name, m.esc_id))?;
            motors.insert(m.esc_id, Arc::new(motor));
        }
        *lock(&self.motors) = motors;
        let ids: Vec<u16> = self.ids.iter().map(|m| m.esc_id).collect();
        for id in ids {
            let period = lock(&self.polls)
                .get(&id)
                .map_or(Duration::ZERO, |p| p.period);
            self.set_poll(id, period);
        }
        Ok(())
    }

    /// Stop every read and drop every handle (their identifiers are free again once the
    /// reads have let go of them).
    async fn close_handles(&self) {
        let tasks: Vec<_> = lock(&self.polls)
            .values_mut()
            .filter_map(|p| p.task.take())
            .collect();
        for task in tasks {
            task.abort();
            let _ = task.await;
        }
        lock(&self.motors).clear();
    }

    /// Read motor `id` every `period` from now on (zero: never).
    fn set_poll(&self, id: u16, period: Duration) {
        let motor = lock(&self.motors).get(&id).cloned();
        let mut polls = lock(&self.polls);
        let poll = polls.entry(id).or_default();
        if let Some(task) = poll.task.take() {
            task.abort();
        }
        poll.period = period;
        if let (Some(motor), false) = (motor, period.is_zero()) {
            poll.task = Some(tokio::spawn(async move {
                let mut ticks = tokio::time::interval(period);
                ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
                loop {
                    ticks.tick().await;
                    // An error state comes back as an error with its feedback, which the
                    // handle keeps all the same; a missed read is the next one's to make up.
                    let _ = motor.refresh().await;
                }
            }));
        }
    }

    fn motor(&self, id: u16) -> Result<Arc<DamiaoMotor>, DeviceError> {
        lock(&self.motors).get(&id).cloned().ok_or_else(|| {
            let ids: Vec<String> = self.ids.iter().map(|m| m.esc_id.to_string()).collect();
            DeviceError::unsupported(format!(
                "no motor with ESC_ID {id} on `{}` (motors: {})",
                self.name,
                ids.join(", ")
            ))
        })
    }

    /// Every motor as the driver last saw it.
    fn observe(&self) -> Observation {
        lock(&self.motors)
            .iter()
            .map(|(id, m)| (*id, MotorObservation::of(m.last_feedback())))
            .collect()
    }
}

impl Drop for DamiaoDevice {
    fn drop(&mut self) {
        for poll in lock(&self.polls).values_mut() {
            if let Some(task) = poll.task.take() {
                task.abort();
            }
        }
    }
}

#[async_trait]
impl Device for DamiaoDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        match action {
            Action::Damiao(a) => self.act(a, timeout).await,
            other => Err(DeviceError::step_of_another_kind(
                &self.name,
                "a Damiao bus",
                other,
            )),
        }
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        let obs = self.observe();
        for check in checks {
            let Check::Damiao(MotorCheck { motor, cond }) = check else {
                return Err((check.describe(), format!("`{}` is a Damiao bus", self.name)));
            };
            if !cond.holds(*motor, &obs) {
                return Err((cond.expected_text(*motor), cond.actual_text(*motor, &obs)));
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        let ids: Vec<u16> = self.ids.iter().map(|m| m.esc_id).collect();
        super::trace::columns(signals, &ids)
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        let obs = self.observe();
        let motors: Vec<_> = self.ids.iter().map(|m| obs.get(&m.esc_id)).collect();
        super::trace::row(signals, &motors)
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        let f = dm_fault(fault, &self.name)?;
        self.motor(f.motor)?;
        self.emulator
            .running()
            .await?
            .inject(f.motor, f.fault.name(), &f.values)
            .await
            .map_err(emulator_error)?;
        lock(&self.active).push(f);
        Ok(())
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        // Clearing removes the cause; the latched error stays until `clear_error` (FB), as on
        // the motor.
        let faults: Vec<DmFault> = match fault {
            Some(f) => {
                let f = dm_fault(f, &self.name)?;
                lock(&self.active).retain(|a| *a != f);
                vec![f]
            }
            None => std::mem::take(&mut *lock(&self.active)),
        };
        for f in faults {
            self.emulator
                .running()
                .await?
                .clear(f.motor, f.fault.name(), &f.values)
                .await
                .map_err(emulator_error)?;
        }
        Ok(())
    }

    async fn emulator_health(&self, last: bool) -> Result<(), String> {
        let ask = || {
            let monitor = self.emulator.try_with(DamiaoHandle::monitor)?;
            Some(async move { monitor.snapshot().await })
        };
        self.health
            .judge(last, ask, |motors| dm_health(motors))
            .await
    }

    async fn shutdown(&self) {
        self.close_handles().await;
        self.emulator.shutdown().await;
    }
}

impl BusEmulator for DamiaoBus {
    type Config = DamiaoConfig;
    type Handle = DamiaoHandle;
    type Error = sim::damiao::DamiaoError;

    fn power_on(config: DamiaoConfig, node: Arc<dyn CanBus>) -> Result<DamiaoHandle, Self::Error> {
        DamiaoBus::spawn(config, node)
    }

    fn power_off(handle: DamiaoHandle) -> impl Future<Output = ()> + Send {
        handle.shutdown()
    }
}

/// An emulator's refusal as a step error.
fn emulator_error(e: sim::damiao::DamiaoError) -> DeviceError {
    DeviceError::unsupported(format!("emulator: {e}"))
}

/// Whether every emulated motor's physical state is finite.
fn dm_health(motors: &[ActuatorSnapshot]) -> Result<(), String> {
    motors_finite(motors.iter().map(|m| MotorPhysics {
        id: m.can_id,
        angle_rad: m.angle_rad,
        speed_rad_s: m.speed_rad_s,
        torque_nm: m.torque_nm,
        temperature_c: m.temperature_c,
    }))
}

/// The Damiao fault inside a device fault (validation routes only Damiao faults here).
fn dm_fault(fault: &DeviceFault, name: &str) -> Result<DmFault, DeviceError> {
    match fault {
        DeviceFault::Damiao(f) => Ok(f.clone()),
        other => Err(DeviceError::fault_of_another_kind(
            name,
            "a Damiao bus",
            other,
        )),
    }
}
