//! Layer 1 of the Damiao grammar: the `motors:` list of a `damiao` device, the `damiao:` step
//! and the per-motor conditions (`motors: {ESC_ID: {...}}`), as written.

use serde::Deserialize;

use crate::devices::contract::motor_bus::{RawMotorBus, RawPerMotor};
use crate::devices::contract::motor_rig::RawLoad;
use crate::scenario::onekey::one_key_enum;
use crate::scenario::S;

/// One motor of a `damiao` device.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDmMotor {
    /// ESC_ID: the identifier it is commanded on.
    pub id: S<i64>,
    pub model: S<String>,
    /// MST_ID: the identifier it answers on (default `id` + 0x10).
    pub feedback_id: Option<S<i64>>,
    /// What its shaft drives on the built-in rig (the same rig a RobStride motor drives).
    pub load: Option<S<RawLoad>>,
    pub start_angle_rad: Option<S<f64>>,
    pub friction_nm_s_per_rad: Option<S<f64>>,
}

/// A Damiao bus's settings (after `kind: damiao`).
pub(crate) type RawSettings = RawMotorBus<RawDmMotor>;

/// The `damiao:` step: `do:` names the command, the other keys are its arguments.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDmStep {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub expect_error: Option<S<String>>,
    #[serde(rename = "do")]
    pub command: Option<S<String>>,
    pub motor: Option<S<i64>>,
    pub p_rad: Option<S<f64>>,
    pub v_rad_s: Option<S<f64>>,
    pub kp: Option<S<f64>>,
    pub kd: Option<S<f64>>,
    pub t_nm: Option<S<f64>>,
    pub i_limit: Option<S<f64>>,
    pub mode: Option<S<String>>,
    pub register: Option<S<String>>,
    pub value: Option<S<f64>>,
    pub expect: Option<S<f64>>,
    pub tolerance: Option<S<f64>>,
    pub period_ms: Option<S<i64>>,
    pub temp_c: Option<S<f64>>,
    pub torque_nm: Option<S<f64>>,
}

/// Conditions on one motor.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMotorConds {
    pub position_rad: Option<S<f64>>,
    pub tolerance_rad: Option<S<f64>>,
    pub velocity_rad_s: Option<S<f64>>,
    pub tolerance_rad_s: Option<S<f64>>,
    pub torque_nm: Option<S<f64>>,
    pub tolerance_nm: Option<S<f64>>,
    pub state: Option<S<String>>,
    pub mos_temp_c: Option<S<f64>>,
    pub rotor_temp_c: Option<S<f64>>,
    pub tolerance_c: Option<S<f64>>,
}

/// Damiao conditions in `expect` and `wait_until`: per motor, by ESC_ID.
pub(crate) type RawConds = RawPerMotor<RawMotorConds>;

one_key_enum! {
    /// Damiao steps.
    pub(crate) enum RawStep ("step") {
        "damiao" => Damiao(Box<RawDmStep>),
    }
}

impl RawStep {
    /// The step's `id:`.
    pub(crate) fn id(&self) -> Option<&S<String>> {
        match self {
            Self::Damiao(a) => a.id.as_ref(),
        }
    }
}

/// A Damiao emulator fault as written: one of the emulator's fault names (its state-nibble
/// errors) and its arguments (`motor`, and the fault's own value), read as every kind's are.
pub(crate) type RawFault = crate::scenario::onekey::NamedEntry<
    sim::damiao::Fault,
    crate::scenario::fault_args::RawFaultArgs,
>;

impl crate::scenario::onekey::NamedKind for sim::damiao::Fault {
    fn all() -> &'static [Self] {
        &Self::ALL
    }

    fn name(self) -> &'static str {
        sim::damiao::Fault::name(self)
    }

    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }
}
