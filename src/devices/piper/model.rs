//! The Piper's validated scenario vocabulary: settings, actions, faults and checks. Every value
//! has been range-checked; units are in the field names.

use std::path::PathBuf;

use crate::scenario::{Near, Pos};

/// Number of joints of a Piper arm.
pub const PIPER_JOINTS: usize = 6;

/// Settings of an emulated Piper.
#[derive(Debug, Clone, PartialEq)]
pub struct PiperSettings {
    /// The bench bus it is on (`bus:`) and where that is written; `None`: the only bus.
    pub bus: Option<(String, Pos)>,
    /// The leader/follower role in flash at power-on (`role:`; a leader starts teaching).
    pub role: Role,
    /// Firmware version string the emulator reports and whose quirks it follows (`S-V1.8-8`).
    pub firmware: String,
    /// URDF to load (absolute, or relative to the working directory); `None` for the default.
    pub urdf: Option<PathBuf>,
    /// Joint angles at power-on.
    pub initial_joints_deg: [f64; PIPER_JOINTS],
    /// Gripper travel set in flash (0 = never set, 70, 100 mm), `None` for the default.
    pub gripper_max_mm: Option<u8>,
    /// Collision-protection levels in flash (0..=8 per joint), `None` for the default (off).
    pub collision_levels: Option<[u8; PIPER_JOINTS]>,
    /// Static obstacles in the arm's world.
    pub obstacles: Vec<Obstacle>,
}

/// A static obstacle.
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    /// Name for logs.
    pub name: String,
    /// Its shape.
    pub shape: ObstacleShape,
    /// Centre in the arm's base frame, metres.
    pub at_m: [f64; 3],
}

/// Obstacle shapes.
#[derive(Debug, Clone, PartialEq)]
pub enum ObstacleShape {
    /// A box with these full edge lengths (metres).
    Box {
        /// Edge lengths x, y, z.
        size_m: [f64; 3],
    },
    /// A sphere.
    Sphere {
        /// Radius.
        radius_m: f64,
    },
}

/// A Cartesian pose of the flange.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// X, Y, Z in millimetres.
    pub position_mm: [f64; 3],
    /// RX, RY, RZ in degrees.
    pub orientation_deg: [f64; 3],
}

/// Piper control modes (0x151 byte 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CtrlMode {
    /// Standby.
    Standby,
    /// CAN command mode.
    Can,
}

/// Piper MOVE modes (0x151 byte 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveMode {
    /// MOVE P.
    P,
    /// MOVE J.
    J,
    /// MOVE L.
    L,
    /// MOVE C.
    C,
    /// MOVE M (MIT).
    M,
}

/// Installation positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Install {
    /// Horizontal upright.
    Upright,
    /// Side mount, left.
    Left,
    /// Side mount, right.
    Right,
}

/// Payload settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Payload {
    /// Empty.
    Empty,
    /// Half.
    Half,
    /// Full.
    Full,
}

/// Leader/follower role.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Teach-input (leader) arm.
    Leader,
    /// Motion-output (follower) arm.
    Follower,
}

/// Piper actions (one per driver entry point).
#[derive(Debug, Clone, PartialEq)]
pub enum PiperAction {
    /// Enable motors and wait for confirmation.
    Enable {
        /// Joints (1..=6); empty = all.
        joints: Vec<u8>,
        /// Include the gripper.
        gripper: bool,
    },
    /// Disable motors and wait for confirmation.
    Disable {
        /// Joints (1..=6); empty = all.
        joints: Vec<u8>,
    },
    /// Set control and MOVE mode.
    Mode {
        /// Control mode.
        ctrl: CtrlMode,
        /// MOVE mode.
        move_mode: MoveMode,
        /// Speed percentage.
        speed_pct: u8,
        /// MIT flag (0xAD).
        mit: bool,
        /// Installation position.
        install: Option<Install>,
    },
    /// MOVE J to joint angles.
    MoveJ {
        /// Target angles.
        joints_deg: [f64; PIPER_JOINTS],
        /// Speed percentage.
        speed_pct: u8,
        /// Re-send the command every this many ms until the next motion step (`every_ms`).
        every_ms: Option<u32>,
    },
    /// MOVE P to a pose.
    MoveP {
        /// Target.
        pose: Pose,
        /// Speed percentage.
        speed_pct: u8,
        /// Re-send the command every this many ms until the next motion step (`every_ms`).
        every_ms: Option<u32>,
    },
    /// MOVE L to a pose.
    MoveL {
        /// Target.
        pose: Pose,
        /// Speed percentage.
        speed_pct: u8,
        /// Re-send the command every this many ms until the next motion step (`every_ms`).
        every_ms: Option<u32>,
    },
    /// MOVE C through three poses.
    MoveC {
        /// Start.
        start: Pose,
        /// Middle.
        middle: Pose,
        /// End.
        end: Pose,
        /// Speed percentage.
        speed_pct: u8,
        /// Re-send the command every this many ms until the next motion step (`every_ms`).
        every_ms: Option<u32>,
    },
    /// One MIT command.
    Mit {
        /// Joint 1..=6.
        joint: u8,
        /// Position target.
        position_deg: f64,
        /// Velocity target.
        velocity_deg_s: f64,
        /// Stiffness.
        kp: f64,
        /// Damping.
        kd: f64,
        /// Feed-forward torque.
        torque_nm: f64,
    },
    /// Gripper command.
    Gripper {
        /// Target stroke.
        stroke_mm: f64,
        /// Torque limit.
        torque_nm: f64,
        /// Enable (false: disable).
        enable: bool,
        /// Clear gripper errors.
        clear_error: bool,
        /// Re-send the command every this many ms until the next gripper or stop step.
        every_ms: Option<u32>,
    },
    /// Set the gripper's zero.
    GripperZero,
    /// Quick e-stop (0x150 = 0x01).
    Estop,
    /// Resume / reset (0x150 = 0x02).
    Reset,
    /// Query the firmware version.
    QueryFirmware {
        /// Expected version string.
        expect: Option<String>,
    },
    /// Query a joint's limits.
    QueryJointLimits {
        /// Joint 1..=6.
        joint: u8,
        /// Expected min angle.
        min_deg: Option<Near>,
        /// Expected max angle.
        max_deg: Option<Near>,
        /// Expected max speed.
        max_speed_rad_s: Option<Near>,
    },
    /// Query a joint's max acceleration.
    QueryJointAcc {
        /// Joint 1..=6.
        joint: u8,
        /// Expected value.
        max_acc_rad_s2: Option<Near>,
    },
    /// Query the end-effector limits.
    QueryEndLimits {
        /// Expected values (linear m/s, angular rad/s, linear m/s², angular rad/s²).
        expect: [Option<Near>; 4],
    },
    /// Query collision levels.
    QueryCollision {
        /// Expected levels.
        expect: Option<[u8; PIPER_JOINTS]>,
    },
    /// Query gripper / teach-pendant parameters.
    QueryGripperParams {
        /// Expected (max stroke mm, teach coefficient %, friction).
        expect: [Option<u16>; 3],
    },
    /// Set a joint's limits (unset fields unchanged).
    SetJointLimits {
        /// Joint 1..=6.
        joint: u8,
        /// Min angle.
        min_deg: Option<f64>,
        /// Max angle.
        max_deg: Option<f64>,
        /// Max speed.
        max_speed_rad_s: Option<f64>,
    },
    /// Set a joint's max acceleration.
    SetJointAcc {
        /// Joint 1..=6 (7 = all).
        joint: u8,
        /// Value.
        max_acc_rad_s2: f64,
    },
    /// Set end-effector limits (unset unchanged).
    SetEndLimits {
        /// Linear m/s, angular rad/s, linear m/s², angular rad/s².
        values: [Option<f64>; 4],
    },
    /// Set collision levels.
    SetCollision {
        /// Levels 0..=8.
        levels: [u8; PIPER_JOINTS],
    },
    /// Set gripper/teach-pendant parameters.
    SetGripperParams {
        /// Max stroke mm.
        max_stroke_mm: Option<u16>,
        /// Teach coefficient %.
        teach_coefficient_pct: Option<u16>,
        /// Friction 1..=10.
        friction: Option<u16>,
    },
    /// Set the current position of a joint as zero.
    SetZero {
        /// Joint 1..=6 (7 = all).
        joint: u8,
    },
    /// Clear a joint's error.
    ClearJointError {
        /// Joint 1..=6 (7 = all).
        joint: u8,
    },
    /// Reset joint limits, speeds and accelerations to defaults.
    ResetParams,
    /// Set the end payload.
    SetPayload {
        /// Payload.
        payload: Payload,
    },
    /// Leader/follower configuration (0x470).
    SetRole {
        /// Role.
        role: Role,
        /// Feedback ID offset (0, 0x10, 0x20).
        feedback_offset: u8,
        /// Control ID offset.
        control_offset: u8,
        /// Linkage target offset.
        target_offset: u8,
    },
}

/// One condition on a device's observed state.
#[derive(Debug, Clone, PartialEq)]
pub enum Check {
    /// Joint angles near targets (`None` = not checked).
    JointsNear {
        /// Targets per joint.
        targets_deg: Vec<Option<f64>>,
        /// Tolerance.
        tolerance_deg: f64,
    },
    /// Joint angles at or above.
    JointsMin {
        /// Bounds per joint.
        bounds_deg: Vec<Option<f64>>,
    },
    /// Joint angles at or below.
    JointsMax {
        /// Bounds per joint.
        bounds_deg: Vec<Option<f64>>,
    },
    /// Every joint's |speed| at or below.
    MaxSpeed {
        /// Bound.
        deg_s: f64,
    },
    /// Every motor's |current| at or below.
    MaxCurrent {
        /// Bound.
        amps: f64,
    },
    /// Flange position near.
    PositionNear {
        /// Target.
        mm: [f64; 3],
        /// Tolerance.
        tolerance_mm: f64,
    },
    /// Flange orientation near.
    OrientationNear {
        /// Target.
        deg: [f64; 3],
        /// Tolerance.
        tolerance_deg: f64,
    },
    /// Gripper stroke near.
    GripperNear {
        /// Target.
        mm: f64,
        /// Tolerance.
        tolerance_mm: f64,
    },
    /// A named status field equals a value (`arm_status`, `ctrl_mode`, `move_mode`, `motion`,
    /// `feedback`, `leader_frames`).
    Status {
        /// Field.
        field: &'static str,
        /// Expected value name.
        value: String,
    },
    /// All joints enabled / disabled.
    Enabled(bool),
    /// Exactly these joints enabled.
    EnabledJoints(Vec<u8>),
    /// Gripper enabled / disabled.
    GripperEnabled(bool),
    /// Exactly these joints have the comm-error bit.
    CommErrorJoints(Vec<u8>),
    /// Exactly these joints have the angle-limit bit.
    LimitErrorJoints(Vec<u8>),
    /// Exactly these fault flags on a joint's driver.
    JointFaults {
        /// Joint 1..=6.
        joint: u8,
        /// Flag names, sorted.
        flags: Vec<String>,
    },
    /// Exactly these gripper fault flags.
    GripperFaults(Vec<String>),
}
