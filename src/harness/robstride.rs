//! RobStride actuators on the bench: the scenario model of the `robstride` device kind (its
//! settings, the `robstride` step's commands, per-motor conditions) and the [`Device`] that
//! drives `driver::robstride` against the in-process `sim::robstride` emulator.
//!
//! Every motor is observed the way the driver sees it: the last status frame (type 2 reply
//! or type 24 active report) and the last type-21 fault report of each CAN ID.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use async_trait::async_trait;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;
use driver::robstride::{
    FaultReport, Feedback, FeedbackKind, Motor, MotorMode, OpControl, Param, ParamValue,
    RobstrideDriver, RobstrideError, RunMode,
};
use sim::robstride::{Fault, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle};

use super::device::{Device, DeviceError, Observation, Reply};
use super::model::{Action, EmulatorFault, ErrorClass, Near};

/// Settings of a `robstride` bench device: the motors on its bus.
#[derive(Debug, Clone, PartialEq)]
pub struct RobstrideSettings {
    /// The emulated motors (CAN ID, model, load), in file order.
    pub motors: Vec<MotorConfig>,
}

/// One `robstride` step: a command to one motor (or, for `restart`, to the whole bus).
#[derive(Debug, Clone, PartialEq)]
pub struct RobstrideAction {
    /// Target CAN ID (0 for bus-wide commands).
    pub motor: u8,
    /// What to do.
    pub command: RsCommand,
}

/// Commands of the `robstride` step.
#[derive(Debug, Clone, PartialEq)]
pub enum RsCommand {
    /// Enable (type 3); the motor must report run mode.
    Enable,
    /// Stop (type 4), optionally clearing latched faults.
    Disable {
        /// Clear latched faults whose cause is gone.
        clear: bool,
    },
    /// Stop, write run_mode, read it back, enable.
    Mode(RunMode),
    /// Operation-control frame (type 1).
    OpControl(OpControl),
    /// Velocity-mode setpoint.
    Velocity {
        /// Speed.
        speed_rad_s: f32,
        /// Current limit.
        limit_cur_a: f32,
        /// Acceleration.
        acc_rad_s2: f32,
    },
    /// Profile-position move.
    Profile {
        /// Target angle.
        target_rad: f32,
        /// Speed limit.
        vel_max_rad_s: f32,
        /// Acceleration.
        acc_rad_s2: f32,
    },
    /// Current-mode setpoint.
    Current {
        /// iq reference.
        iq_a: f32,
    },
    /// Cyclic-synchronous-position setpoint.
    Csp {
        /// Target angle.
        target_rad: f32,
        /// Speed limit.
        limit_spd_rad_s: f32,
    },
    /// Set the mechanical zero here (type 6).
    SetZero,
    /// Stop, set zero, enable again.
    ZeroHere,
    /// Read a parameter and compare it with an expectation.
    ReadParam {
        /// Which parameter.
        param: Param,
        /// Expected value.
        expect: Option<Near>,
    },
    /// Write a parameter (volatile until `save`).
    WriteParam {
        /// Which parameter.
        param: Param,
        /// New value.
        value: f64,
    },
    /// Change the CAN ID (type 7); later steps address the new ID.
    SetCanId {
        /// New ID 1..=127.
        new_id: u8,
    },
    /// Save parameters to flash (type 22).
    Save,
    /// Power-cycle the emulator: motors restart from their saved state.
    Restart,
    /// Active reporting on / off (type 24).
    ActiveReport {
        /// On.
        on: bool,
    },
    /// Active-report period (EPScan_time).
    ReportPeriod {
        /// Period.
        period: Duration,
    },
    /// CAN watchdog window (canTimeout), zero = off.
    CanTimeout {
        /// Window.
        window: Duration,
    },
    /// Ask the motor for its status (type 2 poll).
    Poll,
    /// Emulator: inject a fault (its cause is set, or a one-shot event latched).
    Inject(Fault),
    /// Emulator: remove a fault's cause (the latched bit stays until `disable` with clear).
    RemoveCause(Fault),
    /// Emulator: set the winding temperature.
    SetTemperature {
        /// Temperature.
        temp_c: f64,
    },
    /// Emulator: set the supply voltage.
    SetBusVoltage {
        /// Voltage.
        voltage_v: f64,
    },
    /// Emulator: push the load with an external torque.
    ExternalTorque {
        /// Torque.
        torque_nm: f64,
    },
}

impl RsCommand {
    /// Whether the command acts on the emulator (unavailable against a separate process).
    pub fn needs_emulator(&self) -> bool {
        matches!(
            self,
            Self::Restart
                | Self::Inject(_)
                | Self::RemoveCause(_)
                | Self::SetTemperature { .. }
                | Self::SetBusVoltage { .. }
                | Self::ExternalTorque { .. }
        )
    }

    /// The command's name as written after `do:`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Enable => "enable",
            Self::Disable { .. } => "disable",
            Self::Mode(_) => "mode",
            Self::OpControl(_) => "op_control",
            Self::Velocity { .. } => "velocity",
            Self::Profile { .. } => "profile",
            Self::Current { .. } => "current",
            Self::Csp { .. } => "csp",
            Self::SetZero => "set_zero",
            Self::ZeroHere => "zero_here",
            Self::ReadParam { .. } => "read_param",
            Self::WriteParam { .. } => "write_param",
            Self::SetCanId { .. } => "set_can_id",
            Self::Save => "save",
            Self::Restart => "restart",
            Self::ActiveReport { .. } => "active_report",
            Self::ReportPeriod { .. } => "report_period",
            Self::CanTimeout { .. } => "can_timeout",
            Self::Poll => "poll",
            Self::Inject(_) => "inject",
            Self::RemoveCause(_) => "remove_cause",
            Self::SetTemperature { .. } => "set_temperature",
            Self::SetBusVoltage { .. } => "set_bus_voltage",
            Self::ExternalTorque { .. } => "external_torque",
        }
    }
}

/// Names of the run modes (`mode:`).
pub const RUN_MODES: [(RunMode, &str); 6] = [
    (RunMode::OperationControl, "op_control"),
    (RunMode::ProfilePosition, "profile"),
    (RunMode::Velocity, "velocity"),
    (RunMode::Current, "current"),
    (RunMode::ZeroReturn, "zero_return"),
    (RunMode::CyclicPosition, "csp"),
];

/// Names of the parameters (`param:`).
pub const PARAMS: [(Param, &str); 29] = [
    (Param::RunMode, "run_mode"),
    (Param::IqRef, "iq_ref"),
    (Param::SpdRef, "spd_ref"),
    (Param::LimitTorque, "limit_torque"),
    (Param::CurKp, "cur_kp"),
    (Param::CurKi, "cur_ki"),
    (Param::CurFiltGain, "cur_filt_gain"),
    (Param::LocRef, "loc_ref"),
    (Param::LimitSpd, "limit_spd"),
    (Param::LimitCur, "limit_cur"),
    (Param::MechPos, "mech_pos"),
    (Param::Iqf, "iqf"),
    (Param::MechVel, "mech_vel"),
    (Param::Vbus, "vbus"),
    (Param::LocKp, "loc_kp"),
    (Param::SpdKp, "spd_kp"),
    (Param::SpdKi, "spd_ki"),
    (Param::SpdFiltGain, "spd_filt_gain"),
    (Param::AccRad, "acc_rad"),
    (Param::VelMax, "vel_max"),
    (Param::AccSet, "acc_set"),
    (Param::EpscanTime, "epscan_time"),
    (Param::CanTimeout, "can_timeout"),
    (Param::ZeroSta, "zero_sta"),
    (Param::Damper, "damper"),
    (Param::AddOffset, "add_offset"),
    (Param::AlveolousOpen, "alveolous_open"),
    (Param::IqTest, "iq_test"),
    (Param::DccSet, "dcc_set"),
];

/// Names of the emulator faults (`fault:`).
pub const FAULTS: [(Fault, &str); 9] = [
    (Fault::OverTemperature, "over_temperature"),
    (Fault::UnderVoltage, "under_voltage"),
    (Fault::OverVoltage, "over_voltage"),
    (
        Fault::PhaseOverCurrent(sim::robstride::Phase::A),
        "phase_a_over_current",
    ),
    (
        Fault::PhaseOverCurrent(sim::robstride::Phase::B),
        "phase_b_over_current",
    ),
    (
        Fault::PhaseOverCurrent(sim::robstride::Phase::C),
        "phase_c_over_current",
    ),
    (Fault::EncoderNotCalibrated, "encoder_not_calibrated"),
    (Fault::StallOverload, "stall_overload"),
    (Fault::GateDriver, "gate_driver"),
];

/// Names of the status-frame fault bits (bits 16..21), in bit order.
pub const STATUS_FAULTS: [&str; 6] = [
    "under_voltage",
    "over_current",
    "over_temperature",
    "encoder",
    "stall_overload",
    "uncalibrated",
];

/// Names of the type-21 fault-report flags.
pub const REPORT_FLAGS: [&str; 10] = [
    "over_temperature",
    "gate_driver",
    "under_voltage",
    "over_voltage",
    "phase_a_over_current",
    "phase_b_over_current",
    "phase_c_over_current",
    "uncalibrated",
    "stall_overload",
    "over_temperature_warning",
];

/// Mode-state names (`mode_state:`).
pub const MODE_STATES: [&str; 4] = ["reset", "calibration", "run", "brake"];

/// Kinds of the last feedback frame (`feedback:`).
pub const FEEDBACK_KINDS: [&str; 2] = ["reply", "active_report"];

/// One motor as the driver last saw it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MotorObservation {
    /// Last status frame (`None` before the first one).
    pub angle_rad: Option<f64>,
    /// Speed.
    pub speed_rad_s: Option<f64>,
    /// Torque.
    pub torque_nm: Option<f64>,
    /// Temperature.
    pub temperature_c: Option<f64>,
    /// Mode state name ([`MODE_STATES`]).
    pub mode_state: Option<&'static str>,
    /// Set status-frame fault bits ([`STATUS_FAULTS`]).
    pub status_faults: Vec<&'static str>,
    /// Set flags of the last type-21 report ([`REPORT_FLAGS`]), empty when none came.
    pub fault_report: Vec<&'static str>,
    /// Kind of the last status frame ([`FEEDBACK_KINDS`]).
    pub feedback: Option<&'static str>,
}

/// A condition on one motor (`motors: {ID: {...}}` in `expect` / `wait_until`).
#[derive(Debug, Clone, PartialEq)]
pub enum MotorCond {
    /// Angle near.
    Position(Near),
    /// Speed near.
    Velocity(Near),
    /// Torque near.
    Torque(Near),
    /// Temperature at or above.
    TempMin(f64),
    /// Temperature at or below.
    TempMax(f64),
    /// Mode state equals.
    ModeState(&'static str),
    /// Exactly these status fault bits.
    StatusFaults(Vec<&'static str>),
    /// Exactly these type-21 flags.
    FaultReport(Vec<&'static str>),
    /// Kind of the last status frame.
    Feedback(&'static str),
}

fn f2(v: f64) -> String {
    let t = format!("{v:.2}");
    if t == "-0.00" {
        "0.00".to_owned()
    } else {
        t
    }
}

fn near_text(n: &Near) -> String {
    format!("{} ± {}", f2(n.value), f2(n.tolerance))
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "unknown".to_owned(), f2)
}

impl MotorCond {
    /// What the condition wants, for reports.
    pub fn expected_text(&self, motor: u8) -> String {
        let what = match self {
            Self::Position(n) => format!("position_rad {}", near_text(n)),
            Self::Velocity(n) => format!("velocity_rad_s {}", near_text(n)),
            Self::Torque(n) => format!("torque_nm {}", near_text(n)),
            Self::TempMin(t) => format!("temp_c >= {}", f2(*t)),
            Self::TempMax(t) => format!("temp_c <= {}", f2(*t)),
            Self::ModeState(m) => format!("mode_state {m}"),
            Self::StatusFaults(f) => format!("faults [{}]", f.join(", ")),
            Self::FaultReport(f) => format!("fault_report [{}]", f.join(", ")),
            Self::Feedback(k) => format!("feedback {k}"),
        };
        format!("motor {motor} {what}")
    }

    /// What the motor shows for this condition, for reports.
    pub fn actual_text(&self, motor: u8, obs: &Observation) -> String {
        let Some(m) = obs.motors.get(&motor) else {
            return format!("motor {motor} not on the bus");
        };
        let what = match self {
            Self::Position(_) => format!("position_rad {}", opt(m.angle_rad)),
            Self::Velocity(_) => format!("velocity_rad_s {}", opt(m.speed_rad_s)),
            Self::Torque(_) => format!("torque_nm {}", opt(m.torque_nm)),
            Self::TempMin(_) | Self::TempMax(_) => format!("temp_c {}", opt(m.temperature_c)),
            Self::ModeState(_) => format!("mode_state {}", m.mode_state.unwrap_or("unknown")),
            Self::StatusFaults(_) => format!("faults [{}]", m.status_faults.join(", ")),
            Self::FaultReport(_) => format!("fault_report [{}]", m.fault_report.join(", ")),
            Self::Feedback(_) => format!("feedback {}", m.feedback.unwrap_or("none")),
        };
        format!("motor {motor} {what}")
    }

    /// Whether the condition holds.
    pub fn holds(&self, motor: u8, obs: &Observation) -> bool {
        let Some(m) = obs.motors.get(&motor) else {
            return false;
        };
        let near = |v: Option<f64>, n: &Near| v.is_some_and(|v| (v - n.value).abs() <= n.tolerance);
        match self {
            Self::Position(n) => near(m.angle_rad, n),
            Self::Velocity(n) => near(m.speed_rad_s, n),
            Self::Torque(n) => near(m.torque_nm, n),
            Self::TempMin(t) => m.temperature_c.is_some_and(|v| v >= *t),
            Self::TempMax(t) => m.temperature_c.is_some_and(|v| v <= *t),
            Self::ModeState(s) => m.mode_state == Some(*s),
            Self::StatusFaults(f) => m.status_faults == *f,
            Self::FaultReport(f) => m.fault_report == *f,
            Self::Feedback(k) => m.feedback == Some(*k),
        }
    }
}

fn observe_motor(feedback: Option<Feedback>, report: Option<FaultReport>) -> MotorObservation {
    let mut m = MotorObservation::default();
    if let Some(f) = feedback {
        m.angle_rad = Some(f64::from(f.angle_rad));
        m.speed_rad_s = Some(f64::from(f.speed_rad_s));
        m.torque_nm = Some(f64::from(f.torque_nm));
        m.temperature_c = Some(f64::from(f.temperature_c));
        m.mode_state = Some(match f.mode {
            MotorMode::Reset => "reset",
            MotorMode::Calibration => "calibration",
            MotorMode::Run => "run",
            MotorMode::Brake => "brake",
        });
        m.status_faults = STATUS_FAULTS
            .iter()
            .enumerate()
            .filter(|(bit, _)| f.faults.0 & (1 << bit) != 0)
            .map(|(_, name)| *name)
            .collect();
        m.feedback = Some(match f.kind {
            FeedbackKind::Reply => "reply",
            FeedbackKind::ActiveReport => "active_report",
        });
    }
    if let Some(r) = report {
        let [a, b, c] = r.phase_over_current();
        let flags = [
            r.over_temperature(),
            r.gate_driver(),
            r.under_voltage(),
            r.over_voltage(),
            a,
            b,
            c,
            r.uncalibrated(),
            r.stall_overload(),
            r.over_temperature_warning(),
        ];
        m.fault_report = REPORT_FLAGS
            .iter()
            .zip(flags)
            .filter(|(_, on)| *on)
            .map(|(name, _)| *name)
            .collect();
    }
    m
}

fn classify(error: &RobstrideError) -> ErrorClass {
    match error {
        RobstrideError::Timeout { .. } => ErrorClass::Timeout,
        RobstrideError::Bus(_) | RobstrideError::Closed => ErrorClass::Bus,
        RobstrideError::ParamRefused { .. }
        | RobstrideError::ParamReadFailed { .. }
        | RobstrideError::EnableRefused { .. }
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

/// Distinguishes the state files of concurrent runs in one process.
static STATE_FILES: AtomicU64 = AtomicU64::new(0);

/// A bus of RobStride motors: one driver, one handle per motor, and the emulator.
pub(crate) struct RobstrideDevice {
    name: String,
    /// Owns the receive task that feeds every motor handle (dropping it stops the task).
    _driver: RobstrideDriver,
    motors: Mutex<BTreeMap<u8, Arc<Motor>>>,
    emulator: Option<RsEmulator>,
    handle: tokio::sync::Mutex<Option<RobstrideHandle>>,
    state_dir: Option<PathBuf>,
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
        let mut state_dir = None;
        let mut emulator = None;
        let mut handle = None;
        if let Some(bus) = emulator_bus {
            let dir = std::env::temp_dir().join(format!(
                "armhil-rs-{}-{}-{name}",
                std::process::id(),
                STATE_FILES.fetch_add(1, Ordering::Relaxed)
            ));
            std::fs::create_dir_all(&dir)
                .map_err(|e| format!("device `{name}`: state directory: {e}"))?;
            let mut config = RobstrideConfig::new(settings.motors.clone());
            config.state_file = Some(dir.join("state.json"));
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
            _driver: driver,
            motors: Mutex::new(motors),
            emulator,
            handle: tokio::sync::Mutex::new(handle),
            state_dir,
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
                let uid = result.map_err(derr)?;
                let hex: String = uid.iter().map(|b| format!("{b:02X}")).collect();
                reply.values.push(("can_id".to_owned(), now.to_string()));
                reply.values.push(("uid".to_owned(), hex));
            }
            command => {
                let m = self.motor(id)?;
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
                        let value = raw.as_f64();
                        let name = PARAMS
                            .iter()
                            .find(|(p, _)| p == param)
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
                    | RsCommand::SetCanId { .. } => {}
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
            _ => Err(DeviceError::unsupported(format!(
                "`{}` is a RobStride bus: use `robstride` steps",
                self.name
            ))),
        }
    }

    fn observe(&self) -> Observation {
        let mut obs = Observation::default();
        for (id, motor) in lock(&self.motors).iter() {
            let m = observe_motor(motor.last_feedback(), motor.last_fault_report());
            // The generic signals (trace columns j1.., speeds, temperatures) in CAN ID order.
            obs.joints_deg
                .push(m.angle_rad.map_or(f64::NAN, f64::to_degrees));
            obs.speeds_deg_s
                .push(m.speed_rad_s.map_or(f64::NAN, f64::to_degrees));
            obs.motor_temps_c.push(m.temperature_c.unwrap_or(f64::NAN));
            obs.enabled.push(m.mode_state == Some("run"));
            obs.motors.insert(*id, m);
        }
        obs
    }

    fn inject(&self, fault: &EmulatorFault) -> Result<(), DeviceError> {
        Err(DeviceError::unsupported(format!(
            "`{}` is a RobStride bus: inject `{}` is a Piper fault; use `robstride: {{do: inject, ...}}`",
            self.name,
            fault.describe()
        )))
    }

    fn clear(&self, fault: Option<&EmulatorFault>) -> Result<(), DeviceError> {
        // `clear_faults` (None) also clears bus faults: there is no Piper-style fault to clear
        // here, RobStride faults are cleared by `remove_cause` + `disable` with `clear`.
        if fault.is_none() {
            return Ok(());
        }
        Err(DeviceError::unsupported(format!(
            "`{}` is a RobStride bus: use `robstride: {{do: remove_cause, ...}}` and `disable` with `clear: true`",
            self.name
        )))
    }

    async fn shutdown(&self) {
        if let Some(handle) = self.handle.lock().await.take() {
            handle.shutdown().await;
        }
        lock(&self.motors).clear();
        if let Some(dir) = &self.state_dir {
            // Best effort: a leftover temp directory is harmless.
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

#[cfg(test)]
mod tests {
    use driver::robstride::StatusFaults;

    use super::*;

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
        obs.motors
            .insert(3, observe_motor(Some(feedback(0, MotorMode::Run)), None));
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
    }
}
