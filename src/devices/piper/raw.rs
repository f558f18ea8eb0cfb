//! Layer 1 of the Piper's scenario vocabulary: its settings, steps, faults and conditions as
//! written (shape only; values keep their spans for validation).

use std::collections::BTreeMap;

use serde::Deserialize;

use sim::piper::FaultKind;

use crate::scenario::fault_args::RawFaultArgs;
use crate::scenario::onekey::{one_key_enum, OneKey};
use crate::scenario::read_in::KindSet;
use crate::scenario::S;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
/// A Piper's settings (after `kind: piper`).
pub(crate) struct RawSettings {
    pub bus: Option<S<String>>,
    pub role: Option<S<String>>,
    pub firmware: Option<S<String>>,
    pub urdf: Option<S<String>>,
    pub initial_joints_deg: Option<S<Vec<f64>>>,
    pub gripper_max_mm: Option<S<i64>>,
    pub collision_levels: Option<S<Vec<i64>>>,
    pub obstacles: Option<Vec<S<RawObstacle>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawObstacle {
    pub name: Option<String>,
    pub box_m: Option<S<Vec<f64>>>,
    pub sphere_radius_m: Option<S<f64>>,
    pub at_m: S<Vec<f64>>,
}

/// A Piper emulator fault as written: its kind (named by the emulator's own table,
/// [`sim::piper::FaultKind`]) and arguments.
#[derive(Debug)]
pub(crate) struct RawFault {
    pub kind: FaultKind,
    pub args: RawFaultArgs,
}

impl RawFault {
    /// The fault of `kind` without arguments, if it may be written bare.
    fn bare_of<E: serde::de::Error>(kind: FaultKind) -> Result<Self, E> {
        if kind.bare_ok() {
            Ok(Self {
                kind,
                args: RawFaultArgs::default(),
            })
        } else {
            let key = kind.name();
            Err(E::custom(format!(
                "`{key}` needs arguments: write `{key}: {{ ... }}`"
            )))
        }
    }
}

impl OneKey for RawFault {
    const WHAT: &'static str = "fault";

    fn keys(_: KindSet) -> Vec<&'static str> {
        FaultKind::ALL.iter().map(|k| k.name()).collect()
    }

    fn bare<E: serde::de::Error>(key: &str, _: KindSet) -> Option<Result<Self, E>> {
        FaultKind::from_name(key).map(Self::bare_of)
    }

    fn entry<'de, A: serde::de::MapAccess<'de>>(
        key: &str,
        map: &mut A,
        _: KindSet,
    ) -> Option<Result<Self, A::Error>> {
        let kind = FaultKind::from_name(key)?;
        Some(
            map.next_value::<Option<RawFaultArgs>>()
                .and_then(|args| match args {
                    Some(args) => Ok(Self { kind, args }),
                    None => Self::bare_of(kind),
                }),
        )
    }
}

/// Arguments every device action accepts.
macro_rules! action_args {
    ($name:ident { $($(#[$fm:meta])* $field:ident : $ty:ty),* $(,)? }) => {
        #[derive(Debug, Default, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub(crate) struct $name {
            pub device: Option<S<String>>,
            pub id: Option<S<String>>,
            pub timeout_ms: Option<S<i64>>,
            pub expect_error: Option<S<String>>,
            $($(#[$fm])* pub $field: $ty,)*
        }
    };
}

action_args!(RawEnable { joints: Option<S<Vec<i64>>>, gripper: Option<bool> });
action_args!(RawPlain {});
action_args!(RawMode {
    ctrl: Option<S<String>>,
    #[serde(rename = "move")]
    move_mode: Option<S<String>>,
    speed_pct: Option<S<i64>>,
    mit: Option<bool>,
    install: Option<S<String>>,
});
action_args!(RawMoveJ {
    joints_deg: Option<S<Vec<f64>>>,
    speed_pct: Option<S<i64>>,
    every_ms: Option<S<i64>>,
});
action_args!(RawMovePose {
    position_mm: Option<S<Vec<f64>>>,
    orientation_deg: Option<S<Vec<f64>>>,
    speed_pct: Option<S<i64>>,
    every_ms: Option<S<i64>>,
});
action_args!(RawMoveC {
    start: Option<S<RawPose>>,
    middle: Option<S<RawPose>>,
    end: Option<S<RawPose>>,
    speed_pct: Option<S<i64>>,
    every_ms: Option<S<i64>>,
});
action_args!(RawMit {
    joint: Option<S<i64>>,
    position_deg: Option<S<f64>>,
    velocity_deg_s: Option<S<f64>>,
    kp: Option<S<f64>>,
    kd: Option<S<f64>>,
    torque_nm: Option<S<f64>>,
});
action_args!(RawGripper {
    stroke_mm: Option<S<f64>>,
    torque_nm: Option<S<f64>>,
    enable: Option<bool>,
    clear_error: Option<bool>,
    every_ms: Option<S<i64>>,
});
action_args!(RawJointOnly { joint: Option<S<i64>> });
action_args!(RawQueryFirmware { expect: Option<S<String>> });
action_args!(RawQueryJointLimits { joint: Option<S<i64>>, expect: Option<S<RawJointLimits>> });
action_args!(RawQueryJointAcc { joint: Option<S<i64>>, expect: Option<S<RawJointAcc>> });
action_args!(RawQueryEndLimits { expect: Option<S<RawEndLimits>> });
action_args!(RawQueryCollision { expect: Option<S<RawCollision>> });
action_args!(RawQueryGripperParams { expect: Option<S<RawGripperParams>> });
action_args!(RawSetJointLimits {
    joint: Option<S<i64>>,
    min_deg: Option<S<f64>>,
    max_deg: Option<S<f64>>,
    max_speed_rad_s: Option<S<f64>>,
});
action_args!(RawSetJointAcc { joint: Option<S<i64>>, max_acc_rad_s2: Option<S<f64>> });
action_args!(RawSetEndLimits {
    linear_m_s: Option<S<f64>>,
    angular_rad_s: Option<S<f64>>,
    linear_acc_m_s2: Option<S<f64>>,
    angular_acc_rad_s2: Option<S<f64>>,
});
action_args!(RawSetCollision { levels: Option<S<Vec<i64>>> });
action_args!(RawSetGripperParams {
    max_stroke_mm: Option<S<i64>>,
    teach_coefficient_pct: Option<S<i64>>,
    friction: Option<S<i64>>,
});
action_args!(RawSetPayload { payload: Option<S<String>> });
action_args!(RawSetRole {
    role: Option<S<String>>,
    feedback_offset: Option<S<i64>>,
    control_offset: Option<S<i64>>,
    target_offset: Option<S<i64>>,
});

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPose {
    pub position_mm: S<Vec<f64>>,
    pub orientation_deg: S<Vec<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawJointLimits {
    pub min_deg: Option<S<f64>>,
    pub max_deg: Option<S<f64>>,
    pub max_speed_rad_s: Option<S<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawJointAcc {
    pub max_acc_rad_s2: Option<S<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEndLimits {
    pub linear_m_s: Option<S<f64>>,
    pub angular_rad_s: Option<S<f64>>,
    pub linear_acc_m_s2: Option<S<f64>>,
    pub angular_acc_rad_s2: Option<S<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCollision {
    pub levels: Option<S<Vec<i64>>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawGripperParams {
    pub max_stroke_mm: Option<S<i64>>,
    pub teach_coefficient_pct: Option<S<i64>>,
    pub friction: Option<S<i64>>,
}

/// A Piper's conditions in `expect` and `wait_until`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawConds {
    pub joints_deg: Option<S<Vec<Option<f64>>>>,
    pub tolerance_deg: Option<S<f64>>,
    pub joints_min_deg: Option<S<Vec<Option<f64>>>>,
    pub joints_max_deg: Option<S<Vec<Option<f64>>>>,
    pub max_speed_deg_s: Option<S<f64>>,
    pub position_mm: Option<S<Vec<f64>>>,
    pub orientation_deg: Option<S<Vec<f64>>>,
    pub tolerance_mm: Option<S<f64>>,
    pub gripper_mm: Option<S<f64>>,
    pub arm_status: Option<S<String>>,
    pub ctrl_mode: Option<S<String>>,
    pub move_mode: Option<S<String>>,
    pub motion: Option<S<String>>,
    pub enabled: Option<bool>,
    pub enabled_joints: Option<S<Vec<i64>>>,
    pub gripper_enabled: Option<bool>,
    pub comm_error_joints: Option<S<Vec<i64>>>,
    pub limit_error_joints: Option<S<Vec<i64>>>,
    pub joint_faults: Option<S<BTreeMap<i64, Vec<S<String>>>>>,
    pub gripper_faults: Option<S<Vec<S<String>>>>,
    pub feedback: Option<S<String>>,
    pub leader_frames: Option<bool>,
    pub max_current_a: Option<S<f64>>,
}

/// The keys of [`RawConds`] (which conditions are a Piper's).
pub(crate) const CONDITION_KEYS: [&str; 23] = [
    "joints_deg",
    "tolerance_deg",
    "joints_min_deg",
    "joints_max_deg",
    "max_speed_deg_s",
    "position_mm",
    "orientation_deg",
    "tolerance_mm",
    "gripper_mm",
    "arm_status",
    "ctrl_mode",
    "move_mode",
    "motion",
    "enabled",
    "enabled_joints",
    "gripper_enabled",
    "comm_error_joints",
    "limit_error_joints",
    "joint_faults",
    "gripper_faults",
    "feedback",
    "leader_frames",
    "max_current_a",
];

one_key_enum! {
    /// A Piper's steps.
    pub(crate) enum RawStep ("step") {
        "enable" => Enable(RawEnable) [bare],
        "disable" => Disable(RawEnable) [bare],
        "mode" => Mode(RawMode),
        "move_j" => MoveJ(RawMoveJ),
        "move_p" => MoveP(RawMovePose),
        "move_l" => MoveL(RawMovePose),
        "move_c" => MoveC(RawMoveC),
        "mit" => Mit(RawMit),
        "gripper" => Gripper(RawGripper),
        "gripper_zero" => GripperZero(RawPlain) [bare],
        "estop" => Estop(RawPlain) [bare],
        "reset" => Reset(RawPlain) [bare],
        "query_firmware" => QueryFirmware(RawQueryFirmware) [bare],
        "query_joint_limits" => QueryJointLimits(RawQueryJointLimits),
        "query_joint_max_acc" => QueryJointAcc(RawQueryJointAcc),
        "query_end_limits" => QueryEndLimits(RawQueryEndLimits) [bare],
        "query_collision_levels" => QueryCollision(RawQueryCollision) [bare],
        "query_gripper_params" => QueryGripperParams(RawQueryGripperParams) [bare],
        "set_joint_limits" => SetJointLimits(RawSetJointLimits),
        "set_joint_max_acc" => SetJointAcc(RawSetJointAcc),
        "set_end_limits" => SetEndLimits(RawSetEndLimits),
        "set_collision_levels" => SetCollision(RawSetCollision),
        "set_gripper_params" => SetGripperParams(RawSetGripperParams),
        "set_zero" => SetZero(RawJointOnly),
        "clear_joint_error" => ClearJointError(RawJointOnly),
        "reset_params" => ResetParams(RawPlain) [bare],
        "set_payload" => SetPayload(RawSetPayload),
        "set_role" => SetRole(RawSetRole),
    }
}

impl RawStep {
    /// The step's `id:`.
    pub(crate) fn id(&self) -> Option<&S<String>> {
        macro_rules! id_of {
            ($($variant:ident),*) => {
                match self {
                    $(Self::$variant(args) => args.id.as_ref(),)*
                }
            };
        }
        id_of!(
            Enable,
            Disable,
            Mode,
            MoveJ,
            MoveP,
            MoveL,
            MoveC,
            Mit,
            Gripper,
            GripperZero,
            Estop,
            Reset,
            QueryFirmware,
            QueryJointLimits,
            QueryJointAcc,
            QueryEndLimits,
            QueryCollision,
            QueryGripperParams,
            SetJointLimits,
            SetJointAcc,
            SetEndLimits,
            SetCollision,
            SetGripperParams,
            SetZero,
            ClearJointError,
            ResetParams,
            SetPayload,
            SetRole
        )
    }
}
