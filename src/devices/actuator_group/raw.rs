//! Layer 1 of the `actuator_group` grammar: the actuators, the `group:` step, the joint
//! conditions and the per-actuator fault, as written.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::devices::contract::motor_rig::RawPendulum;
use crate::scenario::onekey::one_key_enum;
use crate::scenario::S;

/// One actuator of the group: the joint it drives and the RobStride motor behind it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawActuator {
    pub joint: S<String>,
    pub can_id: S<i64>,
    pub model: S<String>,
    /// A point mass on a massless arm, hanging from the actuator's shaft.
    pub pendulum: Option<S<RawPendulum>>,
}

/// The group's settings (after `kind: actuator_group`): `actuators` or `robot`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSettings {
    /// Actuators on one bus, each driving its own rig.
    pub actuators: Option<S<Vec<S<RawActuator>>>>,
    /// Or a whole robot: a robot file (`robots/*.yaml`), relative to the scenario.
    pub robot: Option<S<String>>,
    /// The robot's gantry, instead of its file's: `off`, `until_enabled`, `until_released`.
    pub gantry: Option<S<String>>,
}

/// The `group:` step: `do:` names the command (`enable`, `disable`, `hold`, `watchdog`,
/// `mode`, `move`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawGroupStep {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub expect_error: Option<S<String>>,
    #[serde(rename = "do")]
    pub command: Option<S<String>>,
    pub targets_rad: Option<S<BTreeMap<String, S<f64>>>>,
    pub kp: Option<S<f64>>,
    pub kd: Option<S<f64>>,
    pub every_ms: Option<S<i64>>,
    pub window_ms: Option<S<i64>>,
    pub mode: Option<S<String>>,
    pub speed_rad_s: Option<S<f64>>,
}

one_key_enum! {
    /// Actuator-group steps.
    pub(crate) enum RawStep ("step") {
        "group" => Group(Box<RawGroupStep>),
    }
}

impl RawStep {
    /// The step's `id:`.
    pub(crate) fn id(&self) -> Option<&S<String>> {
        match self {
            Self::Group(s) => s.id.as_ref(),
        }
    }
}

/// Conditions on the group in `expect` and `wait_until`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawConds {
    pub joints_rad: Option<S<BTreeMap<String, S<f64>>>>,
    pub tolerance_rad: Option<S<f64>>,
    pub enabled_joints: Option<S<Vec<S<String>>>>,
    pub base_height_m: Option<S<f64>>,
    pub tolerance_m: Option<S<f64>>,
}

/// The keys of [`RawConds`].
pub(crate) const CONDITION_KEYS: [&str; 5] = [
    "joints_rad",
    "tolerance_rad",
    "enabled_joints",
    "base_height_m",
    "tolerance_m",
];

/// `actuator_fault: {joint, fault, …}`: one of the RobStride emulator's faults on one
/// actuator, with the fault's own values (`counts` of an `encoder_glitch`), read as every
/// kind's fault arguments are.
pub(crate) type RawActuatorFault = crate::scenario::fault_args::RawFaultArgs;

one_key_enum! {
    /// Actuator-group faults.
    pub(crate) enum RawFault ("fault") {
        "actuator_fault" => Actuator(RawActuatorFault),
    }
}
