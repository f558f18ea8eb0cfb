//! A Damiao motor in a group: our Damiao driver. `hold` is its MIT command, `move` its
//! position-velocity command; `mode` writes CTRL_MODE (MIT or position-velocity) and reads it
//! back; the watchdog is its CAN timeout register. A Damiao motor sends nothing unasked, so
//! once enabled the group reads its state every [`POLL_PERIOD`] with the refresh request, as
//! a host's control loop does (LeRobot's and the OpenArm library's read state each cycle).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use async_trait::async_trait;
use bus::CanBus;
use driver::damiao::{
    ControlMode, DamiaoDriver, DamiaoError, DamiaoMotor, DriverConfig, Model, MotorState,
};

use sim::actuator::ActuatorConfig;
use sim::damiao::MotorConfig;

use super::{GroupJoint, GroupKind, JointError, KindDrivers};
use crate::devices::actuator_group::model::GroupMode;
use crate::devices::damiao::decode::DamiaoFrames;
use crate::devices::FrameDecoder;
use crate::scenario::ErrorClass;

/// How often the group reads an enabled motor's state.
pub(crate) const POLL_PERIOD: Duration = Duration::from_millis(10);

/// The group's side of Damiao's motors.
pub(crate) struct Damiao;

impl GroupKind for Damiao {
    fn drivers(&self, timeout: Duration) -> Box<dyn KindDrivers> {
        Box::new(DamiaoDrivers::new(timeout))
    }

    fn frames(&self, actuators: &[(Option<String>, &ActuatorConfig)]) -> Box<dyn FrameDecoder> {
        Box::new(DamiaoFrames::of_motors(actuators.iter().filter_map(
            |(bus, a)| {
                let m = a.downcast_ref::<MotorConfig>()?;
                Some((bus.clone(), m.esc_id, m.mst_id, m.model))
            },
        )))
    }
}

/// One Damiao driver per bus, made when its first actuator asks.
pub(crate) struct DamiaoDrivers {
    timeout: Duration,
    by_bus: BTreeMap<usize, DamiaoDriver>,
}

impl DamiaoDrivers {
    fn new(timeout: Duration) -> Self {
        Self {
            timeout,
            by_bus: BTreeMap::new(),
        }
    }

    /// A handle on the motor commanded on `esc_id` and answering on `mst_id` on bus `bus`.
    fn motor(
        &mut self,
        bus: usize,
        host: &Arc<dyn CanBus>,
        esc_id: u16,
        mst_id: u16,
        model: sim::damiao::Model,
    ) -> Result<Arc<dyn GroupJoint>, String> {
        let model = Model::parse(model.name())
            .ok_or_else(|| format!("no driver model {}", model.name()))?;
        let timeout = self.timeout;
        let driver = self.by_bus.entry(bus).or_insert_with(|| {
            DamiaoDriver::new(
                Arc::clone(host),
                DriverConfig {
                    timeout,
                    ..DriverConfig::default()
                },
            )
        });
        let motor = driver
            .motor(esc_id, mst_id, model)
            .map_err(|e| e.to_string())?;
        Ok(Arc::new(DamiaoJoint {
            motor: Arc::new(motor),
            poll: std::sync::Mutex::new(None),
        }))
    }
}

impl KindDrivers for DamiaoDrivers {
    fn joint(
        &mut self,
        bus: usize,
        host: &Arc<dyn CanBus>,
        actuator: &ActuatorConfig,
    ) -> Option<Result<Arc<dyn GroupJoint>, String>> {
        let m = actuator.downcast_ref::<MotorConfig>()?;
        Some(self.motor(bus, host, m.esc_id, m.mst_id, m.model))
    }
}

/// The group's hand on one Damiao motor.
pub(crate) struct DamiaoJoint {
    motor: Arc<DamiaoMotor>,
    /// The state reads, from the first enable on.
    poll: std::sync::Mutex<Option<tokio::task::JoinHandle<()>>>,
}

impl DamiaoJoint {
    /// Starts reading the motor's state every [`POLL_PERIOD`] (once; it goes on while the
    /// group runs, enabled or not, as a host keeps watching its motors).
    fn start_polling(&self) {
        let mut poll = self.poll.lock().unwrap_or_else(|e| e.into_inner());
        if poll.is_some() {
            return;
        }
        let motor = Arc::clone(&self.motor);
        *poll = Some(tokio::spawn(async move {
            let mut ticks = tokio::time::interval(POLL_PERIOD);
            ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
            loop {
                ticks.tick().await;
                // A missed read is the next one's to make up; the checks see stale state.
                let _ = motor.refresh().await;
            }
        }));
    }
}

impl Drop for DamiaoJoint {
    fn drop(&mut self) {
        if let Some(poll) = self.poll.lock().unwrap_or_else(|e| e.into_inner()).take() {
            poll.abort();
        }
    }
}

fn failed(e: DamiaoError) -> JointError {
    let class = match e {
        DamiaoError::Timeout { .. } => ErrorClass::Timeout,
        DamiaoError::Bus(_) | DamiaoError::Closed => ErrorClass::Bus,
        DamiaoError::EnableRefused { .. }
        | DamiaoError::Motor(_)
        | DamiaoError::ModeNotApplied { .. } => ErrorClass::Rejected,
        _ => ErrorClass::InvalidArgument,
    };
    JointError {
        class,
        message: e.to_string(),
    }
}

#[async_trait]
impl GroupJoint for DamiaoJoint {
    async fn enable(&self) -> Result<(), JointError> {
        self.motor.enable().await.map_err(failed)?;
        self.start_polling();
        Ok(())
    }

    async fn disable(&self) -> Result<(), JointError> {
        self.motor.disable().await.map(|_| ()).map_err(failed)
    }

    async fn hold(&self, angle_rad: f64, kp: f64, kd: f64) -> Result<(), JointError> {
        self.motor
            .mit(angle_rad as f32, 0.0, kp as f32, kd as f32, 0.0)
            .await
            .map(|_| ())
            .map_err(failed)
    }

    async fn move_to(&self, angle_rad: f64, speed_rad_s: f64) -> Result<(), JointError> {
        self.motor
            .pos_vel(angle_rad as f32, speed_rad_s as f32)
            .await
            .map(|_| ())
            .map_err(failed)
    }

    async fn switch_mode(&self, mode: GroupMode) -> Result<(), JointError> {
        let mode = match mode {
            GroupMode::Mit => ControlMode::Mit,
            GroupMode::Csp => ControlMode::PosVel,
        };
        self.motor.set_control_mode(mode).await.map_err(failed)
    }

    async fn watchdog(&self, window: Duration) -> Result<(), JointError> {
        self.motor
            .set_can_timeout(window)
            .await
            .map(|_| ())
            .map_err(failed)
    }

    fn angle_rad(&self) -> Option<f64> {
        self.motor
            .last_feedback()
            .map(|f| f64::from(f.position_rad))
    }

    fn is_enabled(&self) -> bool {
        self.motor
            .last_feedback()
            .is_some_and(|f| f.state == MotorState::Enabled)
    }
}
