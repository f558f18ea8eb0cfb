//! The Realman kind's validated vocabulary: settings, the `realman` step's commands, the arm
//! conditions and the emulator faults (the emulator's own fault list and descriptions).

use sim::realman::{RealmanFault, RealmanFaultKind};

use crate::scenario::Near;

/// Settings of a `realman` bench device.
#[derive(Debug, Clone, PartialEq)]
pub struct RealmanSettings {
    /// Product name (`RM65-B`, `RM75-B`).
    pub model: &'static str,
    /// Boot pose, degrees (`None`: all zero).
    pub initial_joints_deg: Option<Vec<f64>>,
    /// Whether a gripper is mounted.
    pub gripper: bool,
    /// TCP connections the driver opens (steps choose one with `client:`).
    pub clients: usize,
}

/// Model names a scenario may give.
pub const MODELS: [(&str, &str); 2] = [("RM65-B", "RM65-B"), ("RM75-B", "RM75-B")];

/// Motion options of a planned move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Motion {
    /// Speed, % of the maximum.
    pub speed: u8,
    /// Blend radius, %.
    pub blend: u8,
    /// Queue with the next move (`trajectory_connect` 1) instead of starting.
    pub queue: bool,
    /// Wait for the arrival event.
    pub block: bool,
}

/// A pose: position (m) and Z-Y-X Euler angles (degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseDeg {
    /// x, y, z, m.
    pub position_m: [f64; 3],
    /// rx, ry, rz, degrees.
    pub euler_deg: [f64; 3],
}

/// How a stream's points reach the controller (docs/protocols/realman.md §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamMode {
    /// `movej_canfd` / `movep_canfd` with `follow: false` (low follow).
    Canfd,
    /// `movej_canfd` / `movep_canfd` with `follow: true` (high follow, period ≤ 10 ms).
    CanfdFollow,
    /// `movej_follow` / `movep_follow` (online planning toward the latest point).
    Follow,
}

/// `mode:` names of a stream.
pub const STREAM_MODES: [(StreamMode, &str); 3] = [
    (StreamMode::Canfd, "canfd"),
    (StreamMode::CanfdFollow, "canfd_follow"),
    (StreamMode::Follow, "follow"),
];

/// What a stream interpolates between.
#[derive(Debug, Clone, PartialEq)]
pub enum StreamPath {
    /// Joint angles, degrees (`stream_joints`).
    Joints {
        /// First point.
        from_deg: Vec<f64>,
        /// Last point.
        to_deg: Vec<f64>,
    },
    /// Poses (`stream_pose`): position and Euler angles interpolated component by component.
    Pose {
        /// First point.
        from: PoseDeg,
        /// Last point.
        to: PoseDeg,
    },
}

/// A stream of passthrough / follow points sent at a fixed period (in the run's clock).
#[derive(Debug, Clone, PartialEq)]
pub struct Stream {
    /// The interpolated path.
    pub path: StreamPath,
    /// Time from the first point to the last, ms.
    pub duration_ms: u32,
    /// Time between points, ms.
    pub period_ms: u32,
    /// Which command carries the points.
    pub mode: StreamMode,
    /// Wait for the last point (`false`: stream in the background while later steps run).
    pub block: bool,
}

/// Cartesian axis of a step or teach jog.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JogAxis {
    /// x (rx for orientation).
    X,
    /// y (ry).
    Y,
    /// z (rz).
    Z,
}

/// `axis:` names.
pub const JOG_AXES: [(JogAxis, &str); 3] =
    [(JogAxis::X, "x"), (JogAxis::Y, "y"), (JogAxis::Z, "z")];

/// What a step or teach jog moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JogTarget {
    /// One joint (1-based): `set_joint_step` / `set_joint_teach`.
    Joint(u8),
    /// The tool position along an axis: `set_pos_step` / `set_pos_teach`.
    Position(JogAxis),
    /// The tool orientation about an axis: `set_ort_step` / `set_ort_teach`.
    Orientation(JogAxis),
}

/// A motion parameter `set_param` / `get_param` name (docs/protocols/realman.md §8, §9).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    /// End-effector line speed, m/s.
    MaxLineSpeed,
    /// End-effector line acceleration, m/s².
    MaxLineAcc,
    /// End-effector angular speed, rad/s.
    MaxAngularSpeed,
    /// End-effector angular acceleration, rad/s².
    MaxAngularAcc,
    /// Collision sensitivity 0..=8.
    CollisionStage,
    /// Self-collision detection, 0 or 1.
    SelfCollision,
    /// One joint's speed limit, °/s.
    JointMaxSpeed,
    /// One joint's acceleration limit, °/s².
    JointMaxAcc,
    /// One joint's lower position limit, °.
    JointMinPos,
    /// One joint's upper position limit, °.
    JointMaxPos,
    /// One DH row's alpha, °.
    DhAlpha,
    /// One DH row's a, m.
    DhA,
    /// One DH row's d, m.
    DhD,
    /// One DH row's offset, °.
    DhOffset,
}

/// Parameter names as written (units in the names) and whether they need `joint:`.
pub const PARAMS: [(Param, &str, bool); 14] = [
    (Param::MaxLineSpeed, "max_line_speed_m_s", false),
    (Param::MaxLineAcc, "max_line_acc_m_s2", false),
    (Param::MaxAngularSpeed, "max_angular_speed_rad_s", false),
    (Param::MaxAngularAcc, "max_angular_acc_rad_s2", false),
    (Param::CollisionStage, "collision_stage", false),
    (Param::SelfCollision, "self_collision", false),
    (Param::JointMaxSpeed, "joint_max_speed_deg_s", true),
    (Param::JointMaxAcc, "joint_max_acc_deg_s2", true),
    (Param::JointMinPos, "joint_min_pos_deg", true),
    (Param::JointMaxPos, "joint_max_pos_deg", true),
    (Param::DhAlpha, "dh_alpha_deg", true),
    (Param::DhA, "dh_a_m", true),
    (Param::DhD, "dh_d_m", true),
    (Param::DhOffset, "dh_offset_deg", true),
];

impl Param {
    /// The name as written.
    pub fn name(self) -> &'static str {
        PARAMS
            .iter()
            .find(|(p, _, _)| *p == self)
            .map_or("?", |(_, n, _)| n)
    }

    /// Whether the parameter belongs to one joint (`joint:` needed).
    pub fn per_joint(self) -> bool {
        PARAMS.iter().any(|(p, _, j)| *p == self && *j)
    }
}

/// One `realman` step.
#[derive(Debug, Clone, PartialEq)]
pub struct RealmanAction {
    /// Which connection sends it (0-based).
    pub client: usize,
    /// What to do.
    pub command: RmCommand,
}

/// Commands of the `realman` step.
#[derive(Debug, Clone, PartialEq)]
pub enum RmCommand {
    /// The connect handshake (11 queries).
    Handshake,
    /// `movej` to joint angles (degrees).
    MoveJ(Vec<f64>, Motion),
    /// `movel` to a pose.
    MoveL(PoseDeg, Motion),
    /// `movej_p` to a pose.
    MoveJP(PoseDeg, Motion),
    /// `movec` through `via` to `to`.
    MoveC {
        /// Via pose.
        via: PoseDeg,
        /// End pose.
        to: PoseDeg,
        /// Extra turns.
        loops: u32,
        /// Options.
        motion: Motion,
    },
    /// Quick stop.
    Stop,
    /// Slow stop.
    SlowStop,
    /// Pause on the path.
    Pause,
    /// Continue after a pause.
    Continue,
    /// Delete every queued move (after a pause).
    DeleteTrajectories,
    /// Clear the controller's errors.
    ClearErrors,
    /// Arm power on / off.
    Power(bool),
    /// Realtime push period and enable.
    Push {
        /// Period, ms (multiple of 5).
        period_ms: u32,
        /// On or off.
        enable: bool,
    },
    /// Gripper to an opening 1–1000.
    GripperPosition {
        /// Opening.
        position: u16,
        /// Wait for the arrival event.
        block: bool,
    },
    /// Gripper force pick.
    GripperPick {
        /// Speed 1–1000.
        speed: u16,
        /// Force 50–1000.
        force: u16,
        /// Wait.
        block: bool,
    },
    /// Gripper release.
    GripperRelease {
        /// Speed 1–1000.
        speed: u16,
        /// Wait.
        block: bool,
    },
    /// Read the gripper opening (and compare it with an expectation).
    ReadGripper {
        /// Expected opening.
        expect: Option<Near>,
    },
    /// Hand posture 1–40.
    HandPosture {
        /// Posture number.
        posture: u8,
        /// Wait.
        block: bool,
    },
    /// Hand finger angles 0–1000 (−1 keeps a finger).
    HandAngles {
        /// Six fingers.
        angles: [Option<u16>; 6],
        /// Wait.
        block: bool,
    },
    /// Read the joint angles over TCP (`get_joint_degree`).
    ReadJoints,
    /// Stream interpolated points (`stream_joints` / `stream_pose`).
    Stream(Stream),
    /// A step jog (`set_joint_step`, `set_pos_step`, `set_ort_step`): a single planned move.
    Step {
        /// What moves.
        target: JogTarget,
        /// Step: degrees for a joint or an orientation, metres for a position.
        amount: f64,
        /// Speed, %.
        speed: u8,
        /// Wait for the arrival event.
        block: bool,
    },
    /// A teach jog (`set_joint_teach`, `set_pos_teach`, `set_ort_teach`): moves until
    /// `set_stop_teach`.
    Teach {
        /// What moves.
        target: JogTarget,
        /// Positive direction.
        positive: bool,
        /// Speed, % of the limit.
        speed: u8,
    },
    /// End a teach jog.
    StopTeach,
    /// Write a motion parameter.
    SetParam {
        /// Which.
        param: Param,
        /// Joint / DH row (1-based) of a per-joint parameter.
        joint: Option<u8>,
        /// Value in the unit the name gives.
        value: f64,
    },
    /// Read a motion parameter (and compare it with an expectation).
    GetParam {
        /// Which.
        param: Param,
        /// Joint / DH row (1-based) of a per-joint parameter.
        joint: Option<u8>,
        /// Expected value.
        expect: Option<Near>,
    },
    /// `set_arm_init`: end-effector limits back to the factory values.
    ResetParams,
    /// `set_DH_data_default`.
    ResetDh,
    /// `set_joint_zero_offset`, degrees per joint.
    SetZeroOffset(Vec<f64>),
    /// `set_joint_en_state`: enable or disable one joint (1-based).
    JointEnable {
        /// Joint.
        joint: u8,
        /// Enable.
        on: bool,
    },
    /// Open the connection again after a drop.
    Reconnect,
}

impl RmCommand {
    /// The command's name as written after `do:`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Handshake => "handshake",
            Self::MoveJ(..) => "movej",
            Self::MoveL(..) => "movel",
            Self::MoveJP(..) => "movej_p",
            Self::MoveC { .. } => "movec",
            Self::Stop => "stop",
            Self::SlowStop => "slow_stop",
            Self::Pause => "pause",
            Self::Continue => "continue",
            Self::DeleteTrajectories => "delete_trajectories",
            Self::ClearErrors => "clear_errors",
            Self::Power(_) => "power",
            Self::Push { .. } => "push",
            Self::GripperPosition { .. } => "gripper_position",
            Self::GripperPick { .. } => "gripper_pick",
            Self::GripperRelease { .. } => "gripper_release",
            Self::ReadGripper { .. } => "read_gripper",
            Self::HandPosture { .. } => "hand_posture",
            Self::HandAngles { .. } => "hand_angles",
            Self::ReadJoints => "read_joints",
            Self::Reconnect => "reconnect",
            Self::Stream(s) => match s.path {
                StreamPath::Joints { .. } => "stream_joints",
                StreamPath::Pose { .. } => "stream_pose",
            },
            Self::Step { target, .. } => match target {
                JogTarget::Joint(_) => "set_joint_step",
                JogTarget::Position(_) => "set_pos_step",
                JogTarget::Orientation(_) => "set_ort_step",
            },
            Self::Teach { target, .. } => match target {
                JogTarget::Joint(_) => "set_joint_teach",
                JogTarget::Position(_) => "set_pos_teach",
                JogTarget::Orientation(_) => "set_ort_teach",
            },
            Self::StopTeach => "set_stop_teach",
            Self::SetParam { .. } => "set_param",
            Self::GetParam { .. } => "get_param",
            Self::ResetParams => "reset_params",
            Self::ResetDh => "reset_dh",
            Self::SetZeroOffset(_) => "set_zero_offset",
            Self::JointEnable { .. } => "joint_enable",
        }
    }
}

/// `arm_state` names: the push's `arm_current_status` strings.
pub const ARM_STATES: [&str; 15] = [
    "idle",
    "move_L",
    "move_J",
    "move_C",
    "move_S",
    "move_through_joint",
    "move_through_pose",
    "move_through_force_pose",
    "move_through_current",
    "stop",
    "slow_stop",
    "pause",
    "current_drag",
    "sensor_drag",
    "tech_demonstration",
];

/// Controller error names (`errors:`) and their codes (docs/protocols/realman.md §12).
pub const ERRORS: [(&str, u32); 12] = [
    ("joint_comms", 0x1001),
    ("beyond_joint_limit", 0x1002),
    ("unreachable", 0x1003),
    ("over_speed", 0x1009),
    ("brake_not_released", 0x100B),
    ("collision", 0x100D),
    ("no_work_frame", 0x100E),
    ("no_tool_frame", 0x100F),
    ("joint_disabled", 0x1010),
    ("arc_planning", 0x1011),
    ("self_collision", 0x1012),
    ("gripper", 0x2001),
];

/// A condition on the arm.
#[derive(Debug, Clone, PartialEq)]
pub enum RmCond {
    /// Every joint within the tolerance of its angle (degrees).
    Joints(Vec<f64>, f64),
    /// Flange position within a distance (m).
    Position([f64; 3], f64),
    /// The push's motion status.
    ArmState(&'static str),
    /// Exactly these controller errors (by name).
    Errors(Vec<&'static str>),
    /// Per-joint enable flags.
    Enabled(Vec<bool>),
    /// Push datagrams over the last second.
    PushHz(Near),
    /// Every driver connection up (or not).
    Connected(bool),
}

/// A Realman emulator fault: the emulator's own value.
#[derive(Debug, Clone, PartialEq)]
pub struct RmFault(pub RealmanFault);

impl RmFault {
    /// Short description for logs and reports: the fault's name, its values and the emulator's
    /// description of its wire effect.
    pub fn describe(&self) -> String {
        let values = match &self.0 {
            RealmanFault::ReplyDelay { delay_ms } => format!(" {delay_ms} ms"),
            RealmanFault::MalformedReply { count } => format!(" x{count}"),
            RealmanFault::UdpLoss { permille } => format!(" {permille}‰"),
            RealmanFault::JointError { joint, code } => format!(" joint {joint} 0x{code:04X}"),
            RealmanFault::GripperFault { bits } => format!(" bits 0x{bits:02X}"),
            _ => String::new(),
        };
        format!(
            "{}{values} ({})",
            self.0.name(),
            self.0.kind().description()
        )
    }

    /// The fault's kind.
    pub fn kind(&self) -> RealmanFaultKind {
        self.0.kind()
    }
}
