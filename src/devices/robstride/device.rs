//! RobStride actuators on the bench: the [`Device`] that drives `driver::robstride` against the
//! in-process `sim::robstride` emulator (or a separate emulator process on a real interface).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use async_trait::async_trait;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use driver::robstride::{
    Feedback, MitMotor, MitStatus, Motor, MotorMode, ParamValue, RobstrideDriver, RobstrideError,
};
use sim::robstride::{RobstrideBus, RobstrideConfig, RobstrideHandle};

use super::model::{MotorCheck, RobstrideAction, RobstrideSettings, RsCommand, RsFault, PARAMS};
use super::observe::{f2, near_text, observe_motor, MotorObservation, Observation};
use crate::devices::{Action, Check, DeviceFault};
use crate::scenario::{ErrorClass, Signal};
use crate::harness::{Device, DeviceError, Reply, TraceColumn};

fn classify(error: &RobstrideError) -> ErrorClass {
    match error {
        RobstrideError::Timeout { .. } => ErrorClass::Timeout,
        RobstrideError::Bus(_) | RobstrideError::Closed => ErrorClass::Bus,
        RobstrideError::ParamRefused { .. }
        | RobstrideError::ParamReadFailed { .. }
        | RobstrideError::EnableRefused { .. }
        | RobstrideError::MitEnableRefused { .. }
        | RobstrideError::ModeNotApplied { .. } => ErrorClass::Rejected,
        _ => ErrorClass::InvalidArgument,
    }
}

fn derr(error: RobstrideError) -> DeviceError {
    DeviceError::new(classify(&error), error.to_string())
}

/// The emulator side: the running bus emulator and what a power cycle needs.
pub(crate) struct RsEmulator {
    /// The virtual bus to re-attach to after a restart.
    pub bus: VirtualBus,
    /// Node name of the emulator.
    pub node: String,
    /// Emulator configuration (with its state file).
    pub config: RobstrideConfig,
}

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
    emulator: Option<RsEmulator>,
    handle: tokio::sync::Mutex<Option<RobstrideHandle>>,
    /// The emulator's state folder; dropping it deletes the folder.
    state_dir: Mutex<Option<tempfile::TempDir>>,
    /// The emulator's state, asked for after the last step and read after the next one (see
    /// [`Device::emulator_health`]).
    health_probe: Mutex<Option<HealthProbe>>,
}

/// A snapshot of every emulated motor, on its way.
type HealthProbe = tokio::task::JoinHandle<
    Result<Vec<sim::robstride::MotorSnapshot>, sim::robstride::RobstrideError>,
>;

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
        let mut state_dir = None;
        let mut emulator = None;
        let mut handle = None;
        if let Some(bus) = emulator_bus {
            let dir = tempfile::Builder::new()
                .prefix(&format!("armhil-rs-{name}-"))
                .tempdir()
                .map_err(|e| format!("device `{name}`: state directory: {e}"))?;
            let mut config = RobstrideConfig::new(settings.motors.clone());
            config.state_file = Some(dir.path().join("state.json"));
            config.bus_bitrate_bps = bitrate_bps;
            let node: Arc<dyn CanBus> = Arc::new(bus.attach(name));
            handle = Some(
                RobstrideBus::spawn(node, config.clone())
                    .map_err(|e| format!("device `{name}`: emulator: {e}"))?,
            );
            emulator = Some(RsEmulator {
                bus: bus.clone(),
                node: name.to_owned(),
                config,
            });
            state_dir = Some(dir);
        }
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
            handle: tokio::sync::Mutex::new(handle),
            state_dir: Mutex::new(state_dir),
            health_probe: Mutex::new(None),
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

    /// An MIT-variant command; the reply carries the angle/speed of Response 1 when there is
    /// one and the value for `mit_read_param`.
    async fn mit_act(
        &self,
        id: u8,
        command: &RsCommand,
        reply: &mut Reply,
    ) -> Result<(), DeviceError> {
        let m = self.mit_motor(id)?;
        let status = match command {
            RsCommand::MitEnable => Some(m.enable().await.map_err(derr)?),
            RsCommand::MitStop => Some(m.stop().await.map_err(derr)?),
            RsCommand::MitControl(cmd) => Some(m.control(*cmd).await.map_err(derr)?),
            RsCommand::MitMode(mode) => Some(m.set_mode(*mode).await.map_err(derr)?),
            RsCommand::MitPosition {
                target_rad,
                limit_spd_rad_s,
            } => Some(
                m.set_position(*target_rad, *limit_spd_rad_s)
                    .await
                    .map_err(derr)?,
            ),
            RsCommand::MitVelocity {
                speed_rad_s,
                limit_cur_a,
            } => Some(
                m.set_velocity(*speed_rad_s, *limit_cur_a)
                    .await
                    .map_err(derr)?,
            ),
            RsCommand::MitZero => Some(m.set_zero().await.map_err(derr)?),
            RsCommand::MitClear => Some(m.clear_faults().await.map_err(derr)?),
            RsCommand::MitReadParam { param, expect } => {
                let raw = m.read_param(*param).await.map_err(derr)?;
                param_reply(reply, *param, raw, expect.as_ref());
                None
            }
            RsCommand::MitSetProtocol(protocol) => {
                m.switch_protocol(*protocol).await.map_err(derr)?;
                None
            }
            RsCommand::MitActiveReport { on } => {
                Some(m.set_active_reporting(*on).await.map_err(derr)?)
            }
            _ => None,
        };
        if let Some(s) = status {
            reply
                .values
                .push(("angle_rad".to_owned(), f2(f64::from(s.angle_rad))));
            reply
                .values
                .push(("speed_rad_s".to_owned(), f2(f64::from(s.speed_rad_s))));
        }
        lock(&self.mit_active).insert(id);
        Ok(())
    }

    async fn emulator_do(
        &self,
        what: impl FnOnce(
            &RobstrideHandle,
        )
            -> futures::future::BoxFuture<'_, Result<(), sim::robstride::RobstrideError>>,
    ) -> Result<(), DeviceError> {
        let guard = self.handle.lock().await;
        let Some(handle) = guard.as_ref() else {
            return Err(DeviceError::unsupported(
                "emulator commands need the in-process emulator (not available with --iface)",
            ));
        };
        what(handle)
            .await
            .map_err(|e| DeviceError::unsupported(format!("emulator: {e}")))
    }

    async fn restart(&self) -> Result<(), DeviceError> {
        let Some(emu) = &self.emulator else {
            return Err(DeviceError::unsupported(
                "restart needs the in-process emulator (not available with --iface)",
            ));
        };
        let mut guard = self.handle.lock().await;
        if let Some(old) = guard.take() {
            old.shutdown().await;
        }
        let node: Arc<dyn CanBus> = Arc::new(emu.bus.attach(&emu.node));
        let handle = RobstrideBus::spawn(node, emu.config.clone())
            .map_err(|e| DeviceError::unsupported(format!("emulator restart: {e}")))?;
        *guard = Some(handle);
        Ok(())
    }

    async fn act(
        &self,
        action: &RobstrideAction,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let fut = self.act_inner(action);
        match timeout {
            Some(limit) => tokio::time::timeout(limit, fut).await.unwrap_or_else(|_| {
                Err(DeviceError::new(
                    ErrorClass::Timeout,
                    format!(
                        "{}: no reply within {} ms",
                        action.command.name(),
                        limit.as_millis()
                    ),
                ))
            }),
            None => fut.await,
        }
    }

    async fn act_inner(&self, action: &RobstrideAction) -> Result<Reply, DeviceError> {
        let id = action.motor;
        let mut reply = Reply::default();
        let fb = |reply: &mut Reply, f: &Feedback| {
            reply
                .values
                .push(("angle_rad".to_owned(), f2(f64::from(f.angle_rad))));
            reply
                .values
                .push(("speed_rad_s".to_owned(), f2(f64::from(f.speed_rad_s))));
        };
        match &action.command {
            RsCommand::Restart => self.restart().await?,
            RsCommand::Inject(fault) => {
                let fault = *fault;
                self.emulator_do(|h| Box::pin(h.inject(id, fault))).await?;
            }
            RsCommand::RemoveCause(fault) => {
                let fault = *fault;
                self.emulator_do(|h| Box::pin(h.clear(id, fault))).await?;
            }
            RsCommand::SetTemperature { temp_c } => {
                let t = *temp_c;
                self.emulator_do(|h| Box::pin(h.set_temperature(id, t)))
                    .await?;
            }
            RsCommand::SetBusVoltage { voltage_v } => {
                let v = *voltage_v;
                self.emulator_do(|h| Box::pin(h.set_bus_voltage(id, v)))
                    .await?;
            }
            RsCommand::ExternalTorque { torque_nm } => {
                let t = *torque_nm;
                self.emulator_do(|h| Box::pin(h.set_external_torque(id, t)))
                    .await?;
            }
            RsCommand::SetCanId { new_id } => {
                // An unknown ID gets the error that lists the known ones.
                drop(self.motor(id)?);
                let Some(arc) = lock(&self.motors).remove(&id) else {
                    return Err(DeviceError::unsupported(format!(
                        "no motor with CAN ID {id}"
                    )));
                };
                let mut motor = match Arc::try_unwrap(arc) {
                    Ok(m) => m,
                    Err(arc) => {
                        lock(&self.motors).insert(id, arc);
                        return Err(DeviceError::unsupported(format!(
                            "motor {id} is busy; cannot change its CAN ID now"
                        )));
                    }
                };
                let result = motor.set_can_id(*new_id).await;
                let now = motor.can_id();
                lock(&self.motors).insert(now, Arc::new(motor));
                for slot in lock(&self.ids).iter_mut().filter(|(_, c)| *c == id) {
                    slot.1 = now;
                }
                let uid = result.map_err(derr)?;
                let hex: String = uid.iter().map(|b| format!("{b:02X}")).collect();
                reply.values.push(("can_id".to_owned(), now.to_string()));
                reply.values.push(("uid".to_owned(), hex));
            }
            command if command.is_mit() => self.mit_act(id, command, &mut reply).await?,
            command => {
                let m = self.motor(id)?;
                // Any private command that gets here addresses the private protocol: the
                // private status is what conditions and traces read again.
                lock(&self.mit_active).remove(&id);
                match command {
                    RsCommand::Enable => fb(&mut reply, &m.enable().await.map_err(derr)?),
                    RsCommand::Disable { clear } => {
                        fb(&mut reply, &m.disable(*clear).await.map_err(derr)?);
                    }
                    RsCommand::Mode(mode) => {
                        fb(&mut reply, &m.switch_mode(*mode).await.map_err(derr)?);
                    }
                    RsCommand::OpControl(cmd) => {
                        fb(&mut reply, &m.op_control(*cmd).await.map_err(derr)?);
                    }
                    RsCommand::Velocity {
                        speed_rad_s,
                        limit_cur_a,
                        acc_rad_s2,
                    } => {
                        m.set_velocity(*speed_rad_s, *limit_cur_a, *acc_rad_s2)
                            .await
                            .map_err(derr)?;
                    }
                    RsCommand::Profile {
                        target_rad,
                        vel_max_rad_s,
                        acc_rad_s2,
                    } => {
                        m.move_profile(*target_rad, *vel_max_rad_s, *acc_rad_s2)
                            .await
                            .map_err(derr)?;
                    }
                    RsCommand::Current { iq_a } => {
                        m.set_current(*iq_a).await.map_err(derr)?;
                    }
                    RsCommand::Csp {
                        target_rad,
                        limit_spd_rad_s,
                    } => {
                        m.set_position(*target_rad, *limit_spd_rad_s)
                            .await
                            .map_err(derr)?;
                    }
                    RsCommand::SetZero => fb(&mut reply, &m.set_zero().await.map_err(derr)?),
                    RsCommand::ZeroHere => fb(&mut reply, &m.zero_here().await.map_err(derr)?),
                    RsCommand::ReadParam { param, expect } => {
                        let raw = m.read_param(*param).await.map_err(derr)?;
                        param_reply(&mut reply, *param, raw, expect.as_ref());
                    }
                    RsCommand::SetProtocol(protocol) => {
                        m.set_protocol(*protocol).await.map_err(derr)?;
                    }
                    RsCommand::WriteParam { param, value } => {
                        m.write_param(*param, *value).await.map_err(derr)?;
                    }
                    RsCommand::Save => {
                        m.save().await.map_err(derr)?;
                    }
                    RsCommand::ActiveReport { on } => {
                        m.set_active_reporting(*on).await.map_err(derr)?;
                    }
                    RsCommand::ReportPeriod { period } => {
                        m.set_report_period(*period).await.map_err(derr)?;
                    }
                    RsCommand::CanTimeout { window } => {
                        m.set_can_timeout(*window).await.map_err(derr)?;
                    }
                    RsCommand::Poll => fb(&mut reply, &m.poll().await.map_err(derr)?),
                    // Handled above.
                    RsCommand::Restart
                    | RsCommand::Inject(_)
                    | RsCommand::RemoveCause(_)
                    | RsCommand::SetTemperature { .. }
                    | RsCommand::SetBusVoltage { .. }
                    | RsCommand::ExternalTorque { .. }
                    | RsCommand::SetCanId { .. }
                    | RsCommand::MitEnable
                    | RsCommand::MitStop
                    | RsCommand::MitControl(_)
                    | RsCommand::MitMode(_)
                    | RsCommand::MitPosition { .. }
                    | RsCommand::MitVelocity { .. }
                    | RsCommand::MitZero
                    | RsCommand::MitClear
                    | RsCommand::MitReadParam { .. }
                    | RsCommand::MitSetProtocol(_)
                    | RsCommand::MitActiveReport { .. } => {}
                }
            }
        }
        Ok(reply)
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
            other => Err(DeviceError::unsupported(format!(
                "`{}` is a RobStride bus: a {} step needs a {} device",
                self.name,
                other.kind_name(),
                other.kind_name()
            ))),
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
        // The emulator answers through its own task: waiting for it between steps would let it
        // run a tick before the next step's frames and shift every recorded run. So the
        // question asked after one step is answered (and judged) after the next one.
        let previous = lock(&self.health_probe).take();
        let verdict = match previous {
            Some(probe) if last || probe.is_finished() => match probe.await {
                Ok(Ok(motors)) => rs_health(&motors),
                // A stopped emulator answers nothing; the steps that need it report that.
                _ => Ok(()),
            },
            Some(probe) => {
                *lock(&self.health_probe) = Some(probe);
                Ok(())
            }
            None => Ok(()),
        };
        if verdict.is_ok() {
            if let Ok(guard) = self.handle.try_lock() {
                if let Some(handle) = guard.as_ref() {
                    let monitor = handle.monitor();
                    let probe = tokio::spawn(async move { monitor.snapshot().await });
                    if last {
                        return match probe.await {
                            Ok(Ok(motors)) => rs_health(&motors),
                            _ => Ok(()),
                        };
                    }
                    *lock(&self.health_probe) = Some(probe);
                }
            }
        }
        verdict
    }

    async fn shutdown(&self) {
        if let Some(handle) = self.handle.lock().await.take() {
            handle.shutdown().await;
        }
        lock(&self.motors).clear();
        lock(&self.mit_motors).clear();
        // Deletes the state folder (best effort: a leftover temp folder is harmless).
        drop(lock(&self.state_dir).take());
    }
}

/// Whether every emulated motor's physical state is finite.
fn rs_health(motors: &[sim::robstride::MotorSnapshot]) -> Result<(), String> {
    crate::devices::finite_state(motors.iter().flat_map(|m| {
        let id = m.can_id;
        [
            (format!("motor {id} angle"), m.angle_rad),
            (format!("motor {id} speed"), m.speed_rad_s),
            (format!("motor {id} torque"), m.torque_nm),
            (format!("motor {id} temperature"), m.temperature_c),
        ]
    }))
}

/// The RobStride fault inside a device fault (validation routes only RobStride faults here).
fn rs_fault(fault: &DeviceFault, name: &str) -> Result<RsFault, DeviceError> {
    match fault {
        DeviceFault::Robstride(f) => Ok(*f),
        other => Err(DeviceError::unsupported(format!(
            "`{name}` is a RobStride bus: `{}` is a {} fault",
            other.describe(),
            other.kind_name()
        ))),
    }
}

/// A read parameter in a step's reply, and a mismatch when it misses the expectation.
fn param_reply(
    reply: &mut Reply,
    param: driver::robstride::Param,
    raw: ParamValue,
    expect: Option<&crate::scenario::Near>,
) {
    let value = raw.as_f64();
    let name = PARAMS
        .iter()
        .find(|(p, _)| *p == param)
        .map_or("value", |(_, n)| n);
    // Integer parameters as integers, floats to the millesimal.
    let shown = match raw {
        ParamValue::F32(_) => format!("{value:.3}"),
        _ => format!("{value}"),
    };
    reply.values.push((name.to_owned(), shown.clone()));
    if let Some(e) = expect {
        if (value - e.value).abs() > e.tolerance + 1e-9 {
            reply
                .mismatches
                .push((name.to_owned(), near_text(e), shown));
        }
    }
}

/// A motor seen through its last MIT Response 1. The variant has no status fault bits and no
/// type-21 report (only a fault flag), so `faults` and `fault_report` read empty; every frame
/// is a reply.
fn observe_mit(s: &MitStatus) -> MotorObservation {
    MotorObservation {
        angle_rad: Some(f64::from(s.angle_rad)),
        speed_rad_s: Some(f64::from(s.speed_rad_s)),
        torque_nm: Some(f64::from(s.torque_nm)),
        temperature_c: Some(f64::from(s.temperature_c)),
        mode_state: Some(match s.mode {
            MotorMode::Reset => "reset",
            MotorMode::Calibration => "calibration",
            MotorMode::Run => "run",
            MotorMode::Brake => "brake",
        }),
        status_faults: Vec::new(),
        fault_report: Vec::new(),
        feedback: Some("reply"),
    }
}

impl RobstrideDevice {
    /// Every motor as the driver last saw it (through the protocol it last spoke).
    fn observe(&self) -> Observation {
        let mit_active = lock(&self.mit_active).clone();
        let mit = lock(&self.mit_motors);
        lock(&self.motors)
            .iter()
            .map(|(id, motor)| {
                let via_mit = mit_active
                    .contains(id)
                    .then(|| mit.get(id).and_then(|m| m.last_status()))
                    .flatten();
                let seen = match via_mit {
                    Some(status) => observe_mit(&status),
                    None => observe_motor(motor.last_feedback(), motor.last_fault_report()),
                };
                (*id, seen)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use driver::robstride::{FaultReport, FeedbackKind, MotorMode, StatusFaults};

    use super::super::model::MotorCond;
    use super::*;
    use crate::scenario::Near;

    fn feedback(faults: u8, mode: MotorMode) -> Feedback {
        Feedback {
            motor_id: 3,
            mode,
            faults: StatusFaults(faults),
            angle_rad: 1.5,
            speed_rad_s: -2.0,
            torque_nm: 0.75,
            temperature_c: 41.0,
            kind: FeedbackKind::ActiveReport,
            timestamp: Duration::ZERO,
        }
    }

    #[test]
    fn status_bits_and_fault_words_map_to_names_in_bit_order() {
        let report = FaultReport {
            fault_word: (1 << 16) | (1 << 5) | (1 << 3),
            warning_word: 1,
        };
        let m = observe_motor(Some(feedback(0x14, MotorMode::Reset)), Some(report));
        assert_eq!(m.status_faults, vec!["over_temperature", "stall_overload"]);
        assert_eq!(
            m.fault_report,
            vec![
                "over_voltage",
                "phase_a_over_current",
                "phase_c_over_current",
                "over_temperature_warning"
            ]
        );
        assert_eq!(m.mode_state, Some("reset"));
        assert_eq!(m.feedback, Some("active_report"));
        assert_eq!(m.angle_rad, Some(1.5));
    }

    #[test]
    fn motor_conditions_judge_the_right_motor() {
        let mut obs = Observation::default();
        obs.insert(3, observe_motor(Some(feedback(0, MotorMode::Run)), None));
        let near = |value, tolerance| Near { value, tolerance };
        assert!(MotorCond::Velocity(near(-2.0, 0.1)).holds(3, &obs));
        assert!(!MotorCond::Velocity(near(2.0, 0.1)).holds(3, &obs));
        assert!(!MotorCond::Velocity(near(-2.0, 0.1)).holds(4, &obs));
        assert!(MotorCond::Torque(near(0.7, 0.1)).holds(3, &obs));
        assert!(MotorCond::TempMin(40.0).holds(3, &obs));
        assert!(!MotorCond::TempMax(40.0).holds(3, &obs));
        assert!(MotorCond::ModeState("run").holds(3, &obs));
        assert!(MotorCond::StatusFaults(vec![]).holds(3, &obs));
        assert!(MotorCond::FaultReport(vec![]).holds(3, &obs));
        assert!(!MotorCond::StatusFaults(vec!["under_voltage"]).holds(3, &obs));
        assert_eq!(
            MotorCond::Position(near(1.0, 0.05)).actual_text(3, &obs),
            "motor 3 position_rad 1.50"
        );
        assert_eq!(
            MotorCond::Position(near(1.0, 0.05)).actual_text(9, &obs),
            "motor 9 not on the bus"
        );
    }

    #[test]
    fn driver_errors_get_the_scenario_error_classes() {
        assert_eq!(
            classify(&RobstrideError::ParamRefused {
                motor: 1,
                index: 0x7019
            }),
            ErrorClass::Rejected
        );
        assert_eq!(
            classify(&RobstrideError::Timeout {
                motor: 1,
                request: "poll",
                after: Duration::from_millis(20)
            }),
            ErrorClass::Timeout
        );
        assert_eq!(
            classify(&RobstrideError::InvalidCanId { id: 0 }),
            ErrorClass::InvalidArgument
        );
        assert_eq!(
            classify(&RobstrideError::MitEnableRefused {
                motor: 1,
                fault: true
            }),
            ErrorClass::Rejected
        );
    }

    #[tokio::test(start_paused = true)]
    async fn a_nan_motor_state_is_an_emulator_error() {
        let bus = VirtualBus::new(bus::virtual_bus::VirtualBusConfig::default());
        let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
        let config = RobstrideConfig::new(vec![sim::robstride::MotorConfig::new(
            4,
            sim::robstride::Model::RS00,
        )]);
        let handle = RobstrideBus::spawn(node, config).unwrap();
        let mut motors = handle.snapshot().await.unwrap();
        handle.shutdown().await;
        assert_eq!(rs_health(&motors), Ok(()));
        motors[0].speed_rad_s = f64::INFINITY;
        let err = rs_health(&motors).unwrap_err();
        assert!(err.contains("motor 4 speed is inf"), "{err}");
    }
}
