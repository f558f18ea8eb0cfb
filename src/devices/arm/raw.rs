//! Layer 1 of the `arm` grammar: a vendor-neutral arm's settings, the `arm:` step and the arm
//! conditions, as written.

use serde::Deserialize;

use crate::scenario::onekey::one_key_enum;
use crate::scenario::S;

/// An arm's settings (after `kind: arm`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSettings {
    pub vendor: Option<S<String>>,
    pub gripper: Option<S<bool>>,
}

/// The `arm:` step: `do:` names an Arm API method, the other keys are its arguments.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawArmStep {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub expect_code: Option<S<String>>,
    #[serde(rename = "do")]
    pub method: Option<S<String>>,
    pub joints_deg: Option<S<Vec<f64>>>,
    pub position_m: Option<S<Vec<f64>>>,
    pub euler_deg: Option<S<Vec<f64>>>,
    pub v: Option<S<i64>>,
    pub r: Option<S<i64>>,
    pub trajectory_connect: Option<S<bool>>,
    pub block: Option<S<bool>>,
    pub position: Option<S<i64>>,
    pub speed: Option<S<i64>>,
    pub force: Option<S<i64>>,
}

/// Arm conditions in `expect` and `wait_until` (the arm as its realtime state shows it).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawConds {
    pub joints_deg: Option<S<Vec<f64>>>,
    pub tolerance_deg: Option<S<f64>>,
    pub position_m: Option<S<Vec<f64>>>,
    pub tolerance_m: Option<S<f64>>,
    pub connected: Option<S<bool>>,
    pub gripper_actpos: Option<S<i64>>,
    pub tolerance_actpos: Option<S<i64>>,
}

/// The keys of [`RawConds`].
pub(crate) const CONDITION_KEYS: [&str; 7] = [
    "joints_deg",
    "tolerance_deg",
    "position_m",
    "tolerance_m",
    "connected",
    "gripper_actpos",
    "tolerance_actpos",
];

one_key_enum! {
    /// Arm steps.
    pub(crate) enum RawStep ("step") {
        "arm" => Arm(Box<RawArmStep>),
    }
}

impl RawStep {
    /// The step's `id:`.
    pub(crate) fn id(&self) -> Option<&S<String>> {
        match self {
            Self::Arm(a) => a.id.as_ref(),
        }
    }
}

/// Arguments of an arm fault.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFaultArgs {}

/// An arm fault as written: one of [`super::model::ArmFaultKind`]'s names.
pub(crate) type RawFault =
    crate::scenario::onekey::NamedEntry<super::model::ArmFaultKind, RawFaultArgs>;

impl crate::scenario::onekey::NamedKind for super::model::ArmFaultKind {
    fn all() -> &'static [Self] {
        &Self::ALL
    }

    fn name(self) -> &'static str {
        super::model::ArmFaultKind::name(self)
    }

    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}
