//! Layer 1 of the RobStride grammar: the `motors:` list of a `robstride` device, the
//! `robstride:` step and the per-motor conditions (`motors: {ID: {...}}`), as written.

use serde::Deserialize;

use crate::devices::contract::motor_bus::{RawMotorBus, RawPerMotor};
use crate::devices::contract::motor_rig::RawLoad;
use crate::scenario::onekey::one_key_enum;
use crate::scenario::S;

/// One motor of a `robstride` device.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRsMotor {
    pub id: S<i64>,
    pub model: S<String>,
    pub load: Option<S<RawLoad>>,
    pub start_angle_rad: Option<S<f64>>,
    pub friction_nm_s_per_rad: Option<S<f64>>,
}

/// The `robstride:` step: `do:` names the command, the other keys are its arguments.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRsStep {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub expect_error: Option<S<String>>,
    #[serde(rename = "do")]
    pub command: Option<S<String>>,
    pub motor: Option<S<i64>>,
    pub clear: Option<S<bool>>,
    pub mode: Option<S<String>>,
    pub angle_rad: Option<S<f64>>,
    pub speed_rad_s: Option<S<f64>>,
    pub kp: Option<S<f64>>,
    pub kd: Option<S<f64>>,
    pub torque_nm: Option<S<f64>>,
    pub limit_cur_a: Option<S<f64>>,
    pub acc_rad_s2: Option<S<f64>>,
    pub target_rad: Option<S<f64>>,
    pub vel_max_rad_s: Option<S<f64>>,
    pub iq_a: Option<S<f64>>,
    pub limit_spd_rad_s: Option<S<f64>>,
    pub param: Option<S<String>>,
    pub value: Option<S<f64>>,
    pub expect: Option<S<f64>>,
    pub tolerance: Option<S<f64>>,
    pub new_id: Option<S<i64>>,
    pub on: Option<S<bool>>,
    pub period_ms: Option<S<i64>>,
    pub window_ms: Option<S<i64>>,
    pub fault: Option<S<String>>,
    pub temp_c: Option<S<f64>>,
    pub voltage_v: Option<S<f64>>,
    pub protocol: Option<S<String>>,
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
    pub temp_min_c: Option<S<f64>>,
    pub temp_max_c: Option<S<f64>>,
    pub mode_state: Option<S<String>>,
    pub faults: Option<S<Vec<S<String>>>>,
    pub fault_report: Option<S<Vec<S<String>>>>,
    pub feedback: Option<S<String>>,
}

/// A RobStride bus's settings (after `kind: robstride`).
pub(crate) type RawSettings = RawMotorBus<RawRsMotor>;

/// RobStride conditions in `expect` and `wait_until`: per motor, by CAN ID.
pub(crate) type RawConds = RawPerMotor<RawMotorConds>;

one_key_enum! {
    /// RobStride steps.
    pub(crate) enum RawStep ("step") {
        "robstride" => Robstride(Box<RawRsStep>),
    }
}

impl RawStep {
    /// The step's `id:`.
    pub(crate) fn id(&self) -> Option<&S<String>> {
        match self {
            Self::Robstride(a) => a.id.as_ref(),
        }
    }
}

/// A RobStride emulator fault as written: one of the emulator's fault names and its arguments
/// (`motor`, and the fault's own values), read as every kind's are.
pub(crate) type RawFault = crate::scenario::onekey::NamedEntry<
    sim::robstride::Fault,
    crate::scenario::fault_args::RawFaultArgs,
>;

impl crate::scenario::onekey::NamedKind for sim::robstride::Fault {
    fn all() -> &'static [Self] {
        &Self::ALL
    }

    fn name(self) -> &'static str {
        sim::robstride::Fault::name(self)
    }

    fn from_name(name: &str) -> Option<Self> {
        sim::robstride::Fault::from_name(name)
    }
}
