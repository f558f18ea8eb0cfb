//! The group on a bench: the RobStride emulator with every actuator on one bus (in-process
//! runs) and one RobStride driver with a motor handle per joint.

use std::sync::Arc;
use std::time::Duration;

use async_trait::async_trait;
use bus::CanBus;
use driver::robstride::{
    DriverConfig, Motor, MotorMode, OpControl, RobstrideDriver, RobstrideError,
};
use sim::robstride::{MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle};
use tokio::sync::Mutex;

use super::model::{GroupAction, GroupCheck, GroupFault, GroupSettings};
use crate::devices::{Action, Check, Device, DeviceError, DeviceFault, Reply, TraceColumn};
use crate::scenario::{ErrorClass, Signal};

/// Quantum of traced angles (rad): a thousandth, so a wrong scale factor still shows.
const RAD_Q: f64 = 0.001;

/// The emulator answering for the group (in-process runs only).
pub(crate) fn spawn_emulator(
    node: Arc<dyn CanBus>,
    settings: &GroupSettings,
    bitrate_bps: u32,
) -> Result<RobstrideHandle, String> {
    let motors = settings
        .actuators
        .iter()
        .map(|a| MotorConfig::new(a.can_id, a.model).with_load(a.load))
        .collect();
    let mut config = RobstrideConfig::new(motors);
    config.bus_bitrate_bps = bitrate_bps;
    RobstrideBus::spawn(node, config).map_err(|e| e.to_string())
}

/// A group of RobStride actuators addressed by joint name.
pub(crate) struct GroupDevice {
    name: String,
    settings: GroupSettings,
    /// One handle per actuator, in settings order.
    motors: Vec<Motor>,
    /// Keeps the receive task alive while the handles are used.
    _driver: RobstrideDriver,
    emulator: Mutex<Option<RobstrideHandle>>,
}

impl GroupDevice {
    /// The driver's handles on `host`, and the emulator when in-process.
    pub(crate) fn start(
        name: &str,
        settings: &GroupSettings,
        host: Arc<dyn CanBus>,
        emulator: Option<RobstrideHandle>,
        timeout: Duration,
    ) -> Result<Self, String> {
        let driver = RobstrideDriver::new(
            host,
            DriverConfig {
                timeout,
                ..DriverConfig::default()
            },
        );
        let motors = settings
            .actuators
            .iter()
            .map(|a| {
                let model = driver::robstride::Model::parse(a.model.name()).ok_or_else(|| {
                    format!("device `{name}`: no driver model {}", a.model.name())
                })?;
                driver
                    .motor(a.can_id, model)
                    .map_err(|e| format!("device `{name}`: joint `{}`: {e}", a.joint))
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(Self {
            name: name.to_owned(),
            settings: settings.clone(),
            motors,
            _driver: driver,
            emulator: Mutex::new(emulator),
        })
    }

    fn joint(&self, index: usize) -> &str {
        &self.settings.actuators[index].joint
    }

    fn angle_rad(&self, index: usize) -> Option<f64> {
        self.motors[index]
            .last_feedback()
            .map(|f| f64::from(f.angle_rad))
    }

    /// Runs `each` on every motor in order; the first failure names its joint.
    async fn on_every_motor<'a, F, Fut>(&'a self, each: F) -> Result<(), DeviceError>
    where
        F: Fn(&'a Motor) -> Fut,
        Fut: std::future::Future<Output = Result<(), RobstrideError>>,
    {
        for (index, motor) in self.motors.iter().enumerate() {
            each(motor).await.map_err(|e| self.error(index, e))?;
        }
        Ok(())
    }

    fn error(&self, index: usize, e: RobstrideError) -> DeviceError {
        let class = match e {
            RobstrideError::Timeout { .. } => ErrorClass::Timeout,
            RobstrideError::Bus(_) | RobstrideError::Closed => ErrorClass::Bus,
            RobstrideError::EnableRefused { .. } | RobstrideError::ParamRefused { .. } => {
                ErrorClass::Rejected
            }
            _ => ErrorClass::InvalidArgument,
        };
        DeviceError::new(class, format!("joint `{}`: {e}", self.joint(index)))
    }

    fn check(&self, check: &GroupCheck) -> Result<(), (String, String)> {
        match check {
            GroupCheck::Joints {
                targets,
                tolerance_rad,
            } => {
                for (name, target) in targets {
                    let actual = self.angle_rad(target.actuator);
                    let holds =
                        actual.is_some_and(|a| (a - target.angle_rad).abs() <= *tolerance_rad);
                    if !holds {
                        return Err((
                            format!("{name} {:.3} ±{tolerance_rad} rad", target.angle_rad),
                            match actual {
                                Some(a) => format!("{name} {a:.3} rad"),
                                None => format!("{name}: no feedback yet"),
                            },
                        ));
                    }
                }
                Ok(())
            }
            GroupCheck::EnabledJoints(want) => {
                // In the file's order, whatever order the check lists them in.
                let enabled: Vec<&str> = (0..self.motors.len())
                    .filter(|i| {
                        self.motors[*i]
                            .last_feedback()
                            .is_some_and(|f| f.mode == MotorMode::Run)
                    })
                    .map(|i| self.joint(i))
                    .collect();
                let holds = enabled.len() == want.len()
                    && want.iter().all(|w| enabled.contains(&w.as_str()));
                if holds {
                    Ok(())
                } else {
                    Err((
                        check.describe(),
                        format!("enabled: [{}]", enabled.join(", ")),
                    ))
                }
            }
        }
    }

    fn group_fault<'f>(&self, fault: &'f DeviceFault) -> Result<&'f GroupFault, DeviceError> {
        match fault {
            DeviceFault::ActuatorGroup(f) => Ok(f),
            other => Err(DeviceError::unsupported(format!(
                "`{}` is not an actuator-group fault",
                other.describe()
            ))),
        }
    }
}

#[async_trait]
impl Device for GroupDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        _timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let Action::ActuatorGroup(action) = action else {
            return Err(DeviceError::unsupported(format!(
                "a {} action on actuator group `{}`",
                action.kind_name(),
                self.name
            )));
        };
        match action {
            GroupAction::Enable => {
                self.on_every_motor(|m| async move {
                    m.enable().await?;
                    // The driver's view follows each motor between commands.
                    m.set_active_reporting(true).await
                })
                .await?
            }
            GroupAction::Disable => {
                self.on_every_motor(|m| async move { m.disable(false).await.map(|_| ()) })
                    .await?
            }
            GroupAction::Hold { targets, kp, kd } => {
                for target in targets {
                    let command = OpControl {
                        angle_rad: target.angle_rad as f32,
                        speed_rad_s: 0.0,
                        kp: *kp as f32,
                        kd: *kd as f32,
                        torque_nm: 0.0,
                    };
                    self.motors[target.actuator]
                        .op_control(command)
                        .await
                        .map_err(|e| self.error(target.actuator, e))?;
                }
            }
        }
        Ok(Reply::default())
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        for check in checks {
            match check {
                Check::ActuatorGroup(c) => self.check(c)?,
                other => {
                    return Err((
                        other.describe(),
                        "not an actuator-group condition".to_owned(),
                    ))
                }
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        if !signals.contains(&Signal::Joints) {
            return Vec::new();
        }
        self.settings
            .actuators
            .iter()
            .map(|a| TraceColumn {
                name: format!("{}_rad", a.joint),
                quantum: RAD_Q,
                group: "angles",
            })
            .collect()
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        if !signals.contains(&Signal::Joints) {
            return Vec::new();
        }
        (0..self.motors.len()).map(|i| self.angle_rad(i)).collect()
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        let f = self.group_fault(fault)?;
        let can_id = self.settings.actuators[f.actuator].can_id;
        match self.emulator.lock().await.as_ref() {
            Some(emulator) => emulator
                .inject(can_id, f.fault)
                .await
                .map_err(|e| DeviceError::unsupported(e.to_string())),
            None => Err(DeviceError::unsupported(
                "faults need the in-process emulator",
            )),
        }
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        let guard = self.emulator.lock().await;
        let Some(emulator) = guard.as_ref() else {
            return Err(DeviceError::unsupported(
                "faults need the in-process emulator",
            ));
        };
        let faults: Vec<(u8, sim::robstride::Fault)> = match fault {
            Some(fault) => {
                let f = self.group_fault(fault)?;
                vec![(self.settings.actuators[f.actuator].can_id, f.fault)]
            }
            None => self
                .settings
                .actuators
                .iter()
                .flat_map(|a| sim::robstride::Fault::ALL.map(|f| (a.can_id, f)))
                .collect(),
        };
        for (can_id, fault) in faults {
            emulator
                .clear(can_id, fault)
                .await
                .map_err(|e| DeviceError::unsupported(e.to_string()))?;
        }
        Ok(())
    }

    async fn shutdown(&self) {
        if let Some(emulator) = self.emulator.lock().await.take() {
            emulator.shutdown().await;
        }
    }
}
