//! Layer 1: the scenario file as written, checked only for shape (serde, unknown keys
//! rejected). Every value that needs a semantic check keeps its span for layer 2.

use std::collections::BTreeMap;

use serde::Deserialize;
use serde_saphyr::Spanned;

use super::onekey::one_key_enum;
use super::robstride_raw::{RawMotorConds, RawRsMotor, RawRsStep};

/// A spanned value.
pub(crate) type S<T> = Spanned<T>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScenario {
    pub name: Option<S<String>>,
    pub description: Option<String>,
    pub tags: Option<Vec<S<String>>>,
    pub bench: S<RawBench>,
    pub record: Option<S<RawRecord>>,
    pub faults: Option<Vec<S<RawFaultEntry>>>,
    pub steps: S<Vec<S<RawStep>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBench {
    pub bus: Option<S<RawBus>>,
    pub devices: S<BTreeMap<String, S<RawDevice>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBus {
    pub bitrate_bps: Option<S<i64>>,
    pub interface: Option<S<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    pub kind: S<String>,
    pub firmware: Option<S<String>>,
    pub urdf: Option<S<String>>,
    pub initial_joints_deg: Option<S<Vec<f64>>>,
    pub gripper_max_mm: Option<S<i64>>,
    pub collision_levels: Option<S<Vec<i64>>>,
    pub obstacles: Option<Vec<S<RawObstacle>>>,
    /// RobStride motors (`kind: robstride`).
    pub motors: Option<S<Vec<S<RawRsMotor>>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawObstacle {
    pub name: Option<String>,
    pub box_m: Option<S<Vec<f64>>>,
    pub sphere_radius_m: Option<S<f64>>,
    pub at_m: S<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRecord {
    pub sample_period_ms: Option<S<i64>>,
    pub signals: Option<Vec<S<String>>>,
    pub candump: Option<bool>,
    pub pcap: Option<bool>,
    pub plot: Option<bool>,
}

/// A fault in the schedule (`at_ms` / `after`) or injected by an `inject` step.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFaultEntry {
    pub at_ms: Option<S<i64>>,
    pub after: Option<S<String>>,
    pub delay_ms: Option<S<i64>>,
    pub duration_ms: Option<S<i64>>,
    pub device: Option<S<String>>,
    pub fault: S<RawFault>,
}

/// Selects frames for a bus fault: by identifier, by sending node, or all.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFrameSel {
    pub id: Option<S<i64>>,
    pub node: Option<S<String>>,
    pub probability: Option<S<f64>>,
    pub seed: Option<u64>,
    pub ms: Option<S<i64>>,
}

/// Arguments of emulator faults; which ones apply depends on the fault (checked in layer 2).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEmuArgs {
    pub joint: Option<S<i64>>,
    pub temp_c: Option<S<f64>>,
    pub voltage_v: Option<S<f64>>,
    pub torque_nm: Option<S<f64>>,
    pub board: Option<S<String>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawNodeArg {
    pub node: Option<S<String>>,
}

one_key_enum! {
    /// Every fault the harness can inject.
    pub(crate) enum RawFault ("fault") {
        "comm_loss" => CommLoss(RawEmuArgs),
        "motor_over_temp" => MotorOverTemp(RawEmuArgs),
        "driver_over_temp" => DriverOverTemp(RawEmuArgs),
        "over_current" => OverCurrent(RawEmuArgs),
        "under_voltage" => UnderVoltage(RawEmuArgs) [bare],
        "driver_error" => DriverError(RawEmuArgs),
        "stall" => Stall(RawEmuArgs),
        "external_torque" => ExternalTorque(RawEmuArgs),
        "collision" => Collision(RawEmuArgs),
        "estop" => Estop(RawEmuArgs) [bare],
        "ntc_over_temp" => NtcOverTemp(RawEmuArgs) [bare],
        "gripper_sensor_fault" => GripperSensor(RawEmuArgs) [bare],
        "teach_button" => TeachButton(RawEmuArgs) [bare],
        "drop" => Drop(RawFrameSel) [bare],
        "delay" => Delay(RawFrameSel),
        "corrupt" => Corrupt(RawFrameSel) [bare],
        "duplicate" => Duplicate(RawFrameSel) [bare],
        "silence" => Silence(RawNodeArg),
        "bus_off" => BusOff(RawNodeArg),
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
action_args!(RawMoveJ { joints_deg: Option<S<Vec<f64>>>, speed_pct: Option<S<i64>> });
action_args!(RawMovePose {
    position_mm: Option<S<Vec<f64>>>,
    orientation_deg: Option<S<Vec<f64>>>,
    speed_pct: Option<S<i64>>,
});
action_args!(RawMoveC {
    start: Option<S<RawPose>>,
    middle: Option<S<RawPose>>,
    end: Option<S<RawPose>>,
    speed_pct: Option<S<i64>>,
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

/// Conditions of `expect` and `wait_until` (and the wait/hold durations of those steps).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawConditions {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub for_ms: Option<S<i64>>,
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
    /// RobStride per-motor conditions by CAN ID.
    pub motors: Option<S<BTreeMap<i64, S<RawMotorConds>>>>,
}

/// `inject` step arguments: the fault, its device and how long it lasts.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawInject {
    pub id: Option<S<String>>,
    pub device: Option<S<String>>,
    pub duration_ms: Option<S<i64>>,
    pub fault: S<RawFault>,
}

one_key_enum! {
    /// Every step a scenario can take.
    pub(crate) enum RawStep ("step") {
        "wait_ms" => WaitMs(S<i64>),
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
        "inject" => Inject(RawInject),
        "clear_faults" => ClearFaults(RawPlain) [bare],
        "expect" => Expect(RawConditions),
        "wait_until" => WaitUntil(RawConditions),
        "robstride" => Robstride(Box<RawRsStep>),
    }
}
