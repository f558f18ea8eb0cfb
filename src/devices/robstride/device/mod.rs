//! RobStride actuators on the bench: the [`Device`] that drives `driver::robstride` against the
//! in-process `sim::robstride` emulator (or a separate emulator process on a real interface).

use std::collections::{BTreeMap, BTreeSet};
use std::future::Future;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use async_trait::async_trait;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use driver::robstride::{MitMotor, Motor, RobstrideDriver};
use sim::robstride::{RobstrideBus, RobstrideConfig, RobstrideHandle};

use super::model::{MotorCheck, RobstrideSettings, RsFault};
use crate::devices::contract::bus_emulator::{BenchEmulator, BusEmulator};
use crate::devices::contract::health::{motors_finite, HealthProbe, MotorPhysics};
use crate::devices::{Action, Check, DeviceFault};
use crate::devices::{Device, DeviceError, Reply, TraceColumn};
use crate::scenario::Signal;

mod actions;
mod observation;
#[cfg(test)]
mod tests;

use actions::derr;

/// A bus of RobStride motors: one driver, one handle per motor, and the emulator.
pub(crate) struct RobstrideDevice {
    name: String,
    /// Owns the receive task that feeds every motor handle (dropping it stops the task).
    driver: RobstrideDriver,
    motors: Mutex<BTreeMap<u8, Arc<Motor>>>,
    /// MIT-variant handles, made on a motor's first MIT command (by current CAN ID).
    mit_motors: Mutex<BTreeMap<u8, Arc<MitMotor>>>,
    /// Motors whose last successful command was an MIT one: conditions and traces read their
    /// Response 1 instead of the private status.
    mit_active: Mutex<BTreeSet<u8>>,
    /// The CAN ID each motor had at power-on (it names the trace columns) and has now.
    ids: Mutex<Vec<(u8, u8)>>,
    /// Emulator faults injected and not yet cleared, so `clear_faults` can undo them.
    active: Mutex<Vec<RsFault>>,
    /// The in-process emulator (none on a real interface).
    emulator: BenchEmulator<RobstrideBus>,
    /// The emulator's state, asked for after the last step and read after the next one (see
    /// [`Device::emulator_health`]).
    health: HealthProbe<Vec<sim::robstride::MotorSnapshot>, sim::robstride::RobstrideError>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A poisoned map of handles is still consistent (inserts and removes are atomic).
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl RobstrideDevice {
    /// Start the emulator (when given a virtual bus) and the driver with a handle per motor.
    pub(crate) fn start(
        name: &str,
        settings: &RobstrideSettings,
        host: Arc<dyn CanBus>,
        emulator_bus: Option<&VirtualBus>,
        bitrate_bps: u32,
        timeout: Duration,
    ) -> Result<Self, String> {
        let emulator = BenchEmulator::start(name, "rs", emulator_bus, |state_file| {
            let mut config = RobstrideConfig::new(settings.motors.clone());
            config.state_file = Some(state_file);
            config.bus_bitrate_bps = bitrate_bps;
            config
        })?;
        let driver = RobstrideDriver::new(
            host,
            driver::robstride::DriverConfig {
                timeout,
                ..Default::default()
            },
        );
        let mut motors = BTreeMap::new();
        for m in &settings.motors {
            let model = driver::robstride::Model::parse(m.model.name())
                .ok_or_else(|| format!("device `{name}`: driver has no model {:?}", m.model))?;
            let motor = driver
                .motor(m.can_id, model)
                .map_err(|e| format!("device `{name}`: motor {}: {e}", m.can_id))?;
            motors.insert(m.can_id, Arc::new(motor));
        }
        Ok(Self {
            name: name.to_owned(),
            driver,
            motors: Mutex::new(motors),
            mit_motors: Mutex::new(BTreeMap::new()),
            mit_active: Mutex::new(BTreeSet::new()),
            ids: Mutex::new(
                settings
                    .motors
                    .iter()
                    .map(|m| (m.can_id, m.can_id))
                    .collect(),
            ),
            active: Mutex::new(Vec::new()),
            emulator,
            health: HealthProbe::new(),
        })
    }

    fn motor(&self, id: u8) -> Result<Arc<Motor>, DeviceError> {
        lock(&self.motors).get(&id).cloned().ok_or_else(|| {
            let ids: Vec<String> = lock(&self.motors).keys().map(u8::to_string).collect();
            DeviceError::unsupported(format!(
                "no motor with CAN ID {id} on `{}` (motors: {})",
                self.name,
                ids.join(", ")
            ))
        })
    }

    /// The MIT handle of motor `id` (made on first use, with the private handle's model).
    fn mit_motor(&self, id: u8) -> Result<Arc<MitMotor>, DeviceError> {
        if let Some(m) = lock(&self.mit_motors).get(&id) {
            return Ok(Arc::clone(m));
        }
        let model = self.motor(id)?.model();
        let m = Arc::new(self.driver.mit_motor(id, model).map_err(derr)?);
        lock(&self.mit_motors).insert(id, Arc::clone(&m));
        Ok(m)
    }
}

#[async_trait]
impl Device for RobstrideDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        match action {
            Action::Robstride(a) => self.act(a, timeout).await,
            other => Err(DeviceError::step_of_another_kind(
                &self.name,
                "a RobStride bus",
                other,
            )),
        }
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        let obs = self.observe();
        for check in checks {
            let Check::Robstride(MotorCheck { motor, cond }) = check else {
                return Err((
                    check.describe(),
                    format!("`{}` is a RobStride bus", self.name),
                ));
            };
            if !cond.holds(*motor, &obs) {
                return Err((cond.expected_text(*motor), cond.actual_text(*motor, &obs)));
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        let ids: Vec<u8> = lock(&self.ids).iter().map(|(first, _)| *first).collect();
        super::trace::columns(signals, &ids)
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        let obs = self.observe();
        let now: Vec<u8> = lock(&self.ids).iter().map(|(_, now)| *now).collect();
        let motors: Vec<_> = now.iter().map(|id| obs.get(id)).collect();
        super::trace::row(signals, &motors)
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        let f = rs_fault(fault, &self.name)?;
        self.motor(f.motor)?;
        self.emulator_do(|h| Box::pin(h.inject(f.motor, f.fault)))
            .await?;
        lock(&self.active).push(f);
        Ok(())
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        // Clearing removes the cause; a latched fault stays until `disable` with `clear`, as
        // on the motor.
        let faults: Vec<RsFault> = match fault {
            Some(f) => {
                let f = rs_fault(f, &self.name)?;
                lock(&self.active).retain(|a| *a != f);
                vec![f]
            }
            None => std::mem::take(&mut *lock(&self.active)),
        };
        for f in faults {
            self.emulator_do(|h| Box::pin(h.clear(f.motor, f.fault)))
                .await?;
        }
        Ok(())
    }

    async fn emulator_health(&self, last: bool) -> Result<(), String> {
        let ask = || {
            let monitor = self.emulator.try_with(RobstrideHandle::monitor)?;
            Some(async move { monitor.snapshot().await })
        };
        self.health
            .judge(last, ask, |motors| rs_health(motors))
            .await
    }

    async fn shutdown(&self) {
        self.emulator.shutdown().await;
        lock(&self.motors).clear();
        lock(&self.mit_motors).clear();
    }
}

impl BusEmulator for RobstrideBus {
    type Config = RobstrideConfig;
    type Handle = RobstrideHandle;
    type Error = sim::robstride::RobstrideError;

    fn power_on(
        config: RobstrideConfig,
        node: Arc<dyn CanBus>,
    ) -> Result<RobstrideHandle, Self::Error> {
        RobstrideBus::spawn(node, config)
    }

    fn power_off(handle: RobstrideHandle) -> impl Future<Output = ()> + Send {
        handle.shutdown()
    }
}

/// Whether every emulated motor's physical state is finite.
fn rs_health(motors: &[sim::robstride::MotorSnapshot]) -> Result<(), String> {
    motors_finite(motors.iter().map(|m| MotorPhysics {
        id: u32::from(m.can_id),
        angle_rad: m.angle_rad,
        speed_rad_s: m.speed_rad_s,
        torque_nm: m.torque_nm,
        temperature_c: m.temperature_c,
    }))
}

/// The RobStride fault inside a device fault (validation routes only RobStride faults here).
fn rs_fault(fault: &DeviceFault, name: &str) -> Result<RsFault, DeviceError> {
    match fault {
        DeviceFault::Robstride(f) => Ok(*f),
        other => Err(DeviceError::fault_of_another_kind(
            name,
            "a RobStride bus",
            other,
        )),
    }
}
