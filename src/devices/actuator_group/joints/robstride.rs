//! A RobStride actuator in a group: our RobStride driver (private protocol).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use async_trait::async_trait;
use bus::CanBus;
use driver::robstride::{
    DriverConfig, Motor, MotorMode, OpControl, RobstrideDriver, RobstrideError, RunMode,
};

use sim::actuator::ActuatorConfig;
use sim::robstride::MotorConfig;

use super::{GroupJoint, GroupKind, JointError, KindDrivers};
use crate::devices::actuator_group::model::GroupMode;
use crate::devices::robstride::decode::RobstrideFrames;
use crate::devices::FrameDecoder;
use crate::scenario::ErrorClass;

/// The group's side of RobStride's actuators.
pub(crate) struct Robstride;

impl GroupKind for Robstride {
    fn drivers(&self, timeout: Duration) -> Box<dyn KindDrivers> {
        Box::new(RobstrideDrivers::new(timeout))
    }

    fn frames(&self, actuators: &[(Option<String>, &ActuatorConfig)]) -> Box<dyn FrameDecoder> {
        Box::new(RobstrideFrames::of_motors(actuators.iter().filter_map(
            |(bus, a)| {
                let m = a.downcast_ref::<MotorConfig>()?;
                Some((bus.clone(), m.can_id, m.model))
            },
        )))
    }
}

/// One RobStride driver per bus, made when its first actuator asks.
pub(crate) struct RobstrideDrivers {
    timeout: Duration,
    by_bus: BTreeMap<usize, RobstrideDriver>,
}

impl RobstrideDrivers {
    fn new(timeout: Duration) -> Self {
        Self {
            timeout,
            by_bus: BTreeMap::new(),
        }
    }

    /// A handle on motor `can_id` of `model` on bus `bus` (node `host`).
    fn motor(
        &mut self,
        bus: usize,
        host: &Arc<dyn CanBus>,
        can_id: u8,
        model: sim::robstride::Model,
    ) -> Result<Arc<dyn GroupJoint>, String> {
        let model = driver::robstride::Model::parse(model.name())
            .ok_or_else(|| format!("no driver model {}", model.name()))?;
        let timeout = self.timeout;
        let driver = self.by_bus.entry(bus).or_insert_with(|| {
            RobstrideDriver::new(
                Arc::clone(host),
                DriverConfig {
                    timeout,
                    ..DriverConfig::default()
                },
            )
        });
        let motor = driver.motor(can_id, model).map_err(|e| e.to_string())?;
        Ok(Arc::new(RobstrideJoint(motor)))
    }
}

impl KindDrivers for RobstrideDrivers {
    fn joint(
        &mut self,
        bus: usize,
        host: &Arc<dyn CanBus>,
        actuator: &ActuatorConfig,
    ) -> Option<Result<Arc<dyn GroupJoint>, String>> {
        let m = actuator.downcast_ref::<MotorConfig>()?;
        Some(self.motor(bus, host, m.can_id, m.model))
    }
}

/// The group's hand on one RobStride motor.
pub(crate) struct RobstrideJoint(pub(crate) Motor);

fn failed(e: RobstrideError) -> JointError {
    let class = match e {
        RobstrideError::Timeout { .. } => ErrorClass::Timeout,
        RobstrideError::Bus(_) | RobstrideError::Closed => ErrorClass::Bus,
        RobstrideError::EnableRefused { .. } | RobstrideError::ParamRefused { .. } => {
            ErrorClass::Rejected
        }
        _ => ErrorClass::InvalidArgument,
    };
    JointError {
        class,
        message: e.to_string(),
    }
}

#[async_trait]
impl GroupJoint for RobstrideJoint {
    async fn enable(&self) -> Result<(), JointError> {
        self.0.enable().await.map_err(failed)?;
        // The driver's view follows the motor between commands.
        self.0.set_active_reporting(true).await.map_err(failed)
    }

    async fn disable(&self) -> Result<(), JointError> {
        self.0.disable(false).await.map(|_| ()).map_err(failed)
    }

    async fn hold(&self, angle_rad: f64, kp: f64, kd: f64) -> Result<(), JointError> {
        let command = OpControl {
            angle_rad: angle_rad as f32,
            speed_rad_s: 0.0,
            kp: kp as f32,
            kd: kd as f32,
            torque_nm: 0.0,
        };
        self.0.op_control(command).await.map(|_| ()).map_err(failed)
    }

    async fn move_to(&self, angle_rad: f64, speed_rad_s: f64) -> Result<(), JointError> {
        self.0
            .set_position(angle_rad as f32, speed_rad_s as f32)
            .await
            .map(|_| ())
            .map_err(failed)
    }

    async fn switch_mode(&self, mode: GroupMode) -> Result<(), JointError> {
        let mode = match mode {
            GroupMode::Mit => RunMode::OperationControl,
            GroupMode::Csp => RunMode::CyclicPosition,
        };
        self.0.switch_mode(mode).await.map(|_| ()).map_err(failed)
    }

    async fn watchdog(&self, window: Duration) -> Result<(), JointError> {
        self.0
            .set_can_timeout(window)
            .await
            .map(|_| ())
            .map_err(failed)
    }

    fn angle_rad(&self) -> Option<f64> {
        self.0.last_feedback().map(|f| f64::from(f.angle_rad))
    }

    fn is_enabled(&self) -> bool {
        self.0
            .last_feedback()
            .is_some_and(|f| f.mode == MotorMode::Run)
    }
}
