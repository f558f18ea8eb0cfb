//! Layer 1 of the Realman grammar: the `realman` device's settings, the `realman:` step and the
//! arm conditions, as written.

use serde::Deserialize;

use crate::scenario::onekey::one_key_enum;
use crate::scenario::S;

/// A Realman arm's settings (after `kind: realman`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSettings {
    pub model: Option<S<String>>,
    pub initial_joints_deg: Option<S<Vec<f64>>>,
    pub gripper: Option<S<bool>>,
    pub clients: Option<S<i64>>,
}

/// The `realman:` step: `do:` names the command, the other keys are its arguments.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRmStep {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub expect_error: Option<S<String>>,
    #[serde(rename = "do")]
    pub command: Option<S<String>>,
    pub client: Option<S<i64>>,
    pub joints_deg: Option<S<Vec<f64>>>,
    pub position_m: Option<S<Vec<f64>>>,
    pub euler_deg: Option<S<Vec<f64>>>,
    pub via_position_m: Option<S<Vec<f64>>>,
    pub via_euler_deg: Option<S<Vec<f64>>>,
    pub loops: Option<S<i64>>,
    pub speed: Option<S<i64>>,
    pub blend: Option<S<i64>>,
    pub queue: Option<S<bool>>,
    pub block: Option<S<bool>>,
    pub position: Option<S<i64>>,
    pub force: Option<S<i64>>,
    pub posture: Option<S<i64>>,
    pub angles: Option<S<Vec<i64>>>,
    pub period_ms: Option<S<i64>>,
    pub enable: Option<S<bool>>,
    pub on: Option<S<bool>>,
    pub expect: Option<S<f64>>,
    pub tolerance: Option<S<f64>>,
    // Streams (`stream_joints`, `stream_pose`).
    pub from_deg: Option<S<Vec<f64>>>,
    pub to_deg: Option<S<Vec<f64>>>,
    pub from_position_m: Option<S<Vec<f64>>>,
    pub from_euler_deg: Option<S<Vec<f64>>>,
    pub duration_ms: Option<S<i64>>,
    pub mode: Option<S<String>>,
    // Step and teach jogs.
    pub joint: Option<S<i64>>,
    pub axis: Option<S<String>>,
    pub direction: Option<S<String>>,
    pub step_deg: Option<S<f64>>,
    pub step_m: Option<S<f64>>,
    // Motion parameters.
    pub name: Option<S<String>>,
    pub value: Option<S<f64>>,
}

/// Realman conditions in `expect` and `wait_until` (the arm as the driver's push feed and
/// connections show it).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawConds {
    pub joints_deg: Option<S<Vec<f64>>>,
    pub tolerance_deg: Option<S<f64>>,
    pub position_m: Option<S<Vec<f64>>>,
    pub tolerance_m: Option<S<f64>>,
    pub arm_state: Option<S<String>>,
    pub errors: Option<S<Vec<S<String>>>>,
    pub joints_enabled: Option<S<Vec<bool>>>,
    pub push_hz: Option<S<f64>>,
    pub tolerance_hz: Option<S<f64>>,
    pub connected: Option<S<bool>>,
}

/// The keys of [`RawConds`].
pub(crate) const CONDITION_KEYS: [&str; 10] = [
    "joints_deg",
    "tolerance_deg",
    "position_m",
    "tolerance_m",
    "arm_state",
    "errors",
    "joints_enabled",
    "push_hz",
    "tolerance_hz",
    "connected",
];

one_key_enum! {
    /// Realman steps.
    pub(crate) enum RawStep ("step") {
        "realman" => Realman(Box<RawRmStep>),
    }
}

impl RawStep {
    /// The step's `id:`.
    pub(crate) fn id(&self) -> Option<&S<String>> {
        match self {
            Self::Realman(a) => a.id.as_ref(),
        }
    }
}

/// A Realman emulator fault as written: one of the emulator's fault names and its arguments,
/// read as every kind's are.
pub(crate) type RawFault = crate::scenario::onekey::NamedEntry<
    sim::realman::RealmanFaultKind,
    crate::scenario::fault_args::RawFaultArgs,
>;

impl crate::scenario::onekey::NamedKind for sim::realman::RealmanFaultKind {
    fn all() -> &'static [Self] {
        &Self::ALL
    }

    fn name(self) -> &'static str {
        sim::realman::RealmanFaultKind::name(self)
    }

    fn from_name(name: &str) -> Option<Self> {
        sim::realman::RealmanFaultKind::from_name(name)
    }
}
