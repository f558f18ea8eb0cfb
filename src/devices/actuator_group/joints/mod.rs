//! The group's hand on one actuator, whatever its kind: what a `group:` step asks of a joint
//! (enable, hold, move, a mode, a watchdog) said in that kind's protocol by our own driver.
//! A robot file may mix kinds; each joint gets the driver of its actuator's kind.

mod damiao;
mod robstride;

use std::sync::Arc;
use std::time::Duration;

use async_trait::async_trait;
use bus::CanBus;
use sim::actuator::ActuatorConfig;

use super::model::{GroupActuator, GroupMode};
use crate::devices::FrameDecoder;
use crate::scenario::ErrorClass;

/// Why a joint's command failed, classed as scenario errors are.
#[derive(Debug)]
pub(crate) struct JointError {
    /// What kind of failure (a timeout, a refusal …).
    pub class: ErrorClass,
    /// The driver's message.
    pub message: String,
}

/// One actuator as the group drives it.
#[async_trait]
pub(crate) trait GroupJoint: Send + Sync {
    /// Enable it (it holds where it is) and have it report on its own where the kind can.
    async fn enable(&self) -> Result<(), JointError>;
    /// Torque off.
    async fn disable(&self) -> Result<(), JointError>;
    /// One MIT-style command: hold `angle_rad` with stiffness `kp` and damping `kd`.
    async fn hold(&self, angle_rad: f64, kp: f64, kd: f64) -> Result<(), JointError>;
    /// Go to `angle_rad` at most at `speed_rad_s` (the kind's position mode).
    async fn move_to(&self, angle_rad: f64, speed_rad_s: f64) -> Result<(), JointError>;
    /// Switch to the kind's mode for `hold` (MIT) or `move` (a position mode).
    async fn switch_mode(&self, mode: GroupMode) -> Result<(), JointError>;
    /// Arm the actuator's CAN watchdog: no command for `window` and it stops.
    async fn watchdog(&self, window: Duration) -> Result<(), JointError>;
    /// Its angle as it last reported it (rad), if it has.
    fn angle_rad(&self) -> Option<f64>;
    /// Whether its last report said it is enabled.
    fn is_enabled(&self) -> bool;
}

/// The group's side of one actuator kind: its drivers and its frames. Each kind's file
/// (`joints/<kind>.rs`) implements it on a unit struct, and one line in [`KINDS`] registers it.
pub(crate) trait GroupKind: Sync {
    /// Its drivers for one run (one per bus, made when its first actuator asks), waiting
    /// `timeout` for each reply.
    fn drivers(&self, timeout: Duration) -> Box<dyn KindDrivers>;
    /// Its actuators among `actuators` (each with its bus's name, when it has one), their
    /// frames named by its decoder.
    fn frames(&self, actuators: &[(Option<String>, &ActuatorConfig)]) -> Box<dyn FrameDecoder>;
}

/// One kind's drivers on every bus.
pub(crate) trait KindDrivers: Send + Sync {
    /// A handle on `actuator` on bus `bus` (node `host`), when it is this kind's (`None`: it
    /// is another kind's).
    fn joint(
        &mut self,
        bus: usize,
        host: &Arc<dyn CanBus>,
        actuator: &ActuatorConfig,
    ) -> Option<Result<Arc<dyn GroupJoint>, String>>;
}

/// Every actuator kind a group drives, in the order a joint's kind and a frame's decoder are
/// looked for: one registration line each.
pub(crate) static KINDS: &[&dyn GroupKind] = &[&robstride::Robstride, &damiao::Damiao];

/// The drivers of every kind on every bus, and a joint handle per actuator.
pub(crate) struct Joints {
    /// One per actuator, in settings order.
    pub handles: Vec<Arc<dyn GroupJoint>>,
    /// Keeps the drivers' receive tasks alive while the handles are used.
    _drivers: Vec<Box<dyn KindDrivers>>,
}

impl Joints {
    /// A handle per actuator of `actuators` on `hosts` (one per bus), each by the driver of
    /// its kind. Each driver reads every frame of its host node, so a bus carries one kind:
    /// the group's settings refuse two at load (`validate::robot_settings`).
    pub(crate) fn start(
        device: &str,
        actuators: &[GroupActuator],
        hosts: Vec<Arc<dyn CanBus>>,
        timeout: Duration,
    ) -> Result<Self, String> {
        let mut drivers: Vec<Box<dyn KindDrivers>> =
            KINDS.iter().map(|k| k.drivers(timeout)).collect();
        let mut handles: Vec<Arc<dyn GroupJoint>> = Vec::with_capacity(actuators.len());
        for a in actuators {
            let host = hosts.get(a.bus).ok_or_else(|| {
                format!("device `{device}`: joint `{}`: no bus {}", a.joint, a.bus)
            })?;
            let handle = drivers
                .iter_mut()
                .find_map(|d| d.joint(a.bus, host, &a.actuator))
                .unwrap_or_else(|| {
                    Err(format!(
                        "no driver for a {} actuator",
                        a.actuator.kind().name
                    ))
                })
                .map_err(|e| format!("device `{device}`: joint `{}`: {e}", a.joint))?;
            handles.push(handle);
        }
        Ok(Self {
            handles,
            _drivers: drivers,
        })
    }
}
