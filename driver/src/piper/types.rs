//! The types of the public Piper API: SI units (rad, rad/s, m, N·m, s) and typed enums.
//! Wire integers, "unchanged" sentinels and per-firmware codes live in [`super::codec`] only;
//! the conversions between the two are in `codec::si`.

use super::codec::{self, ArmStatusCode, CtrlMode, JointMask, MotionStatus, TeachStatus};

/// A MOVE mode as the caller means it; the driver picks the firmware's wire code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum MoveKind {
    /// MOVE P (Cartesian point to point, firmware IK).
    P,
    /// MOVE J (joint space, smoothed).
    J,
    /// MOVE L (linear).
    L,
    /// MOVE C (circular, points via [`super::Piper::move_c_point`]).
    C,
    /// MIT pass-through (0x04, or 0x06 from S-V1.8-8), with the 0xAD flag.
    Mit,
    /// MOVE CPV.
    Cpv,
    /// "High-follow": joint targets passed through without smoothing (MOVE J + 0xAD).
    HighFollow,
}

/// The MOVE mode the arm reports (0x2A1), whatever code its firmware uses for MIT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ActiveMove {
    /// MOVE P.
    P,
    /// MOVE J.
    J,
    /// MOVE L.
    L,
    /// MOVE C.
    C,
    /// MIT pass-through (either firmware code).
    Mit,
    /// MOVE CPV.
    Cpv,
    /// A code the spec does not define, kept as received.
    Unknown(u8),
}

impl ActiveMove {
    /// Every defined mode (the one table of names).
    pub const ALL: &'static [Self] = &[Self::P, Self::J, Self::L, Self::C, Self::Mit, Self::Cpv];

    /// The mode's name (`p`, `j`, `l`, `c`, `m`, `cpv`), `None` for [`Self::Unknown`].
    pub fn name(self) -> Option<&'static str> {
        match self {
            Self::P => Some("p"),
            Self::J => Some("j"),
            Self::L => Some("l"),
            Self::C => Some("c"),
            Self::Mit => Some("m"),
            Self::Cpv => Some("cpv"),
            Self::Unknown(_) => None,
        }
    }

    /// True when a [`MoveKind`] command selects this mode.
    pub fn matches(self, kind: MoveKind) -> bool {
        matches!(
            (self, kind),
            (Self::P, MoveKind::P)
                | (Self::J, MoveKind::J | MoveKind::HighFollow)
                | (Self::L, MoveKind::L)
                | (Self::C, MoveKind::C)
                | (Self::Mit, MoveKind::Mit)
                | (Self::Cpv, MoveKind::Cpv)
        )
    }
}

impl std::fmt::Display for ActiveMove {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self, self.name()) {
            (_, Some(name)) => f.write_str(name),
            (Self::Unknown(raw), None) => write!(f, "unknown(0x{raw:02X})"),
            (_, None) => f.write_str("unknown"),
        }
    }
}

/// Installation position of the arm (fw >= V1.5-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Install {
    /// Horizontal upright.
    Upright,
    /// Side mount, left.
    SideLeft,
    /// Side mount, right.
    SideRight,
}

/// A mode command (0x151) in typed form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ModeCommand {
    /// Control mode to enter (usually [`CtrlMode::CanCommand`] or [`CtrlMode::Standby`]).
    pub control: CtrlMode,
    /// MOVE mode.
    pub move_kind: MoveKind,
    /// Speed, percent of the maximum (0–100).
    pub speed_pct: u8,
    /// The MIT (0xAD) flag; `None` sends the flag `move_kind` implies.
    pub mit_flag: Option<bool>,
    /// Installation position; `None` keeps the current one.
    pub install: Option<Install>,
}

/// A mode command a leader arm emitted on the bus (0x151 seen by the driver).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct LeaderMode {
    /// Control mode.
    pub control: CtrlMode,
    /// MOVE mode (`None`: "keep").
    pub move_mode: Option<ActiveMove>,
    /// Speed, percent.
    pub speed_pct: u8,
    /// The MIT (0xAD) flag is set.
    pub mit_flag: bool,
    /// Installation position (`None`: "keep").
    pub install: Option<Install>,
}

/// A Cartesian flange pose: position in m and ZYX Euler angles (RX, RY, RZ) in rad.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Pose {
    /// X, Y, Z, m.
    pub position_m: [f64; 3],
    /// RX, RY, RZ, rad.
    pub orientation_rad: [f64; 3],
}

/// The MOVE C points (0x158).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum CirclePoint {
    /// Start point.
    Start,
    /// Middle point.
    Middle,
    /// End point.
    End,
}

/// A gripper command in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GripperCommand {
    /// Target stroke (jaw opening), m.
    pub stroke_m: f64,
    /// Torque limit, N·m (0–5 in the SDK).
    pub effort_nm: f64,
    /// Enable the gripper driver.
    pub enable: bool,
    /// Clear the gripper error.
    pub clear_error: bool,
}

/// Which joints a joint-configuration command (0x475) addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum JointSelect {
    /// One joint, 1–6.
    Joint(u8),
    /// All six joints.
    All,
}

/// Angle limits and max speed of one joint (0x473 reply).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct JointLimits {
    /// Joint 1–6.
    pub joint: u8,
    /// Lower angle limit, rad.
    pub min_rad: f64,
    /// Upper angle limit, rad.
    pub max_rad: f64,
    /// Max speed, rad/s.
    pub max_speed_rad_s: f64,
}

/// A change of a joint's limits (0x474): each `None` field keeps the arm's value.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct JointLimitsUpdate {
    /// Lower angle limit, rad.
    pub min_rad: Option<f64>,
    /// Upper angle limit, rad.
    pub max_rad: Option<f64>,
    /// Max speed, rad/s.
    pub max_speed_rad_s: Option<f64>,
}

/// End-effector velocity / acceleration limits (0x478 reply).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EndLimits {
    /// Max linear velocity, m/s.
    pub linear_m_s: f64,
    /// Max angular velocity, rad/s.
    pub angular_rad_s: f64,
    /// Max linear acceleration, m/s².
    pub linear_acc_m_s2: f64,
    /// Max angular acceleration, rad/s².
    pub angular_acc_rad_s2: f64,
}

/// A change of the end-effector limits (0x479): each `None` field keeps the arm's value.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct EndLimitsUpdate {
    /// Max linear velocity, m/s.
    pub linear_m_s: Option<f64>,
    /// Max angular velocity, rad/s.
    pub angular_rad_s: Option<f64>,
    /// Max linear acceleration, m/s².
    pub linear_acc_m_s2: Option<f64>,
    /// Max angular acceleration, rad/s².
    pub angular_acc_rad_s2: Option<f64>,
}

/// Gripper / teach-pendant parameters (0x47E reply).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GripperTeachParams {
    /// Teach-pendant travel coefficient, percent (100–200).
    pub teach_coefficient_pct: u8,
    /// Max gripper stroke, m (0 = not set; 0.07 small, 0.1 large gripper).
    pub max_stroke_m: f64,
    /// Teach-pendant friction coefficient, 1–10.
    pub friction: u8,
}

/// A change of the gripper / teach-pendant parameters: each `None` field keeps the arm's
/// value (the driver reads the current values first, since 0x47D has no "keep" code).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct GripperTeachUpdate {
    /// Teach-pendant travel coefficient, percent (100–200).
    pub teach_coefficient_pct: Option<u8>,
    /// Max gripper stroke, m (whole millimetres on the wire, up to 0.255 m).
    pub max_stroke_m: Option<f64>,
    /// Teach-pendant friction coefficient, 1–10.
    pub friction: Option<u8>,
}

/// End-effector payload setting (0x477).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum EndPayload {
    /// Empty.
    Empty,
    /// Half load.
    Half,
    /// Full load.
    Full,
}

/// Leader/follower role of an arm (0x470).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ArmRole {
    /// Teach-input (leader) arm.
    Leader,
    /// Motion-output (follower) arm.
    Follower,
}

/// CAN id offsets of a leader/follower configuration (0x470).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
pub struct RoleOffsets {
    /// Feedback id offset (0x2Ax → 0x2Bx / 0x2Cx): 0, 0x10 or 0x20.
    pub feedback: IdShift,
    /// Control id offset this arm listens on (0x15x → 0x16x / 0x17x).
    pub control: IdShift,
    /// Id offset a leader emits on.
    pub target: IdShift,
}

/// A CAN id offset of the leader/follower configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
pub enum IdShift {
    /// No offset (restore the default ids).
    #[default]
    None,
    /// +0x10.
    Plus10,
    /// +0x20.
    Plus20,
}

impl IdShift {
    /// The offset from its size in ids (0, 0x10 or 0x20); `None` for any other.
    pub fn from_ids(offset: u16) -> Option<Self> {
        match offset {
            0 => Some(Self::None),
            0x10 => Some(Self::Plus10),
            0x20 => Some(Self::Plus20),
            _ => None,
        }
    }
}

/// An offline-trajectory acknowledgement (0x476 for 0x150 transfers and the index query).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct TrajectoryAck {
    /// Trajectory point index acknowledged.
    pub point: u8,
    /// Package name index (the current index for the index query).
    pub name_index: u16,
    /// Package CRC-16.
    pub crc16: u16,
}

/// Arm status (0x2A1), typed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ArmStatus {
    /// Control mode.
    pub ctrl_mode: CtrlMode,
    /// Arm status code.
    pub status: ArmStatusCode,
    /// Active MOVE mode.
    pub move_mode: ActiveMove,
    /// Drag-teach status.
    pub teach: TeachStatus,
    /// Target reached or moving.
    pub motion: MotionStatus,
    /// Current offline-trajectory point.
    pub trajectory_point: u8,
    /// Joints whose angle limit is exceeded.
    pub angle_limit_exceeded: JointMask,
    /// Joints with a communication error.
    pub comm_error: JointMask,
}

/// Flange pose reported by the arm (0x2A2–0x2A4).
pub type EndPose = Pose;

/// Gripper feedback (0x2A8) in SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct GripperState {
    /// Jaw opening, m (0 = closed).
    pub stroke_m: f64,
    /// Torque, N·m.
    pub torque_nm: f64,
    /// Status bits.
    pub status: codec::GripperStatus,
}

/// Fast joint-driver feedback (0x251–0x256) in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MotorState {
    /// Joint 1–6.
    pub joint: u8,
    /// Motor speed, rad/s.
    pub speed_rad_s: f64,
    /// Motor current, A (signed).
    pub current_a: f64,
    /// Motor position, rad.
    pub position_rad: f64,
    /// The SDK's effort estimate from the current, N·m.
    pub effort_nm: f64,
}

/// Slow joint-driver feedback (0x261–0x266) in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DriverState {
    /// Joint 1–6.
    pub joint: u8,
    /// Bus voltage, V.
    pub bus_voltage_v: f64,
    /// Driver temperature, °C.
    pub driver_temp_c: f64,
    /// Motor temperature, °C.
    pub motor_temp_c: f64,
    /// Status bits.
    pub status: codec::DriverStatus,
    /// Bus current, A.
    pub bus_current_a: f64,
}

/// Per-joint end velocity / acceleration feedback (0x481–0x486) in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EndMotion {
    /// Joint 1–6.
    pub joint: u8,
    /// Linear velocity, m/s.
    pub linear_m_s: f64,
    /// Angular velocity, rad/s.
    pub angular_rad_s: f64,
    /// Linear acceleration, m/s².
    pub linear_acc_m_s2: f64,
    /// Angular acceleration, rad/s².
    pub angular_acc_rad_s2: f64,
}
