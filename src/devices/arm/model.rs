//! The `arm` kind's validated vocabulary: settings, the `arm` step's Arm API calls, the
//! conditions and the faults every vendor has.

use driver::arm::{AbcErrorCode, Vendor};

/// Settings of an `arm` bench device.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmSettings {
    /// Whose arm (and emulator) this is.
    pub vendor: Vendor,
    /// Whether the gripper is enabled.
    pub gripper: bool,
}

/// Motion options (`v`, `r`, `trajectory_connect`, `block`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MoveArgs {
    /// `v`: speed, % of the maximum.
    pub v: u8,
    /// `r`: blend radius, %.
    pub r: u8,
    /// Queue with the next move.
    pub trajectory_connect: bool,
    /// Wait for arrival.
    pub block: bool,
}

/// A flange pose: position (m) and Z-Y-X Euler angles (degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseDeg {
    /// x, y, z, m.
    pub position_m: [f64; 3],
    /// rx, ry, rz, degrees.
    pub euler_deg: [f64; 3],
}

/// One Arm API call.
#[derive(Debug, Clone, PartialEq)]
pub enum ArmCall {
    /// `connect`.
    Connect,
    /// `disconnect`.
    Disconnect,
    /// `move_joint_position`.
    MoveJointPosition(Vec<f64>, MoveArgs),
    /// `move_cartesian_linear`.
    MoveCartesianLinear(PoseDeg, MoveArgs),
    /// `move_joint_pose`.
    MoveJointPose(PoseDeg, MoveArgs),
    /// `move_joint_follow`.
    MoveJointFollow(Vec<f64>),
    /// `set_arm_stop`.
    Stop,
    /// `set_arm_slow_stop`.
    SlowStop,
    /// `set_arm_pause`.
    Pause,
    /// `set_arm_continue`.
    Continue,
    /// `set_gripper_position` (0–1000).
    GripperPosition {
        /// Aperture, 1–1000.
        position: u16,
        /// Wait until it stops.
        block: bool,
    },
    /// `set_gripper_release`.
    GripperRelease {
        /// Speed, 1–1000.
        speed: u16,
        /// Wait until it stops.
        block: bool,
    },
    /// `set_gripper_pick`.
    GripperPick {
        /// Speed, 1–1000.
        speed: u16,
        /// Force threshold, 50–1000.
        force: u16,
        /// Wait until it stops.
        block: bool,
    },
    /// `get_joint_degree` (the reply names the angles).
    GetJointDegree,
    /// `get_gripper_state` (the reply names position and force).
    GetGripperState,
}

/// One `arm` step.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmAction {
    /// The call.
    pub call: ArmCall,
    /// The call must fail with this code (it succeeding, or failing otherwise, fails the step).
    pub expect_code: Option<AbcErrorCode>,
}

/// A condition on the arm's realtime state.
#[derive(Debug, Clone, PartialEq)]
pub enum ArmCond {
    /// Joint angles within a tolerance, degrees.
    Joints(Vec<f64>, f64),
    /// Flange position within a tolerance, metres.
    Position([f64; 3], f64),
    /// Whether the arm is connected.
    Connected(bool),
    /// Gripper aperture (0 closed – 1000 open) within a tolerance.
    GripperActpos(i32, i32),
}

impl ArmCond {
    /// What the condition wants, for reports.
    pub fn expected_text(&self) -> String {
        match self {
            Self::Joints(j, tol) => format!("joints_deg {j:?} ±{tol}"),
            Self::Position(p, tol) => format!("position_m {p:?} ±{tol}"),
            Self::Connected(c) => format!("connected {c}"),
            Self::GripperActpos(a, tol) => format!("gripper_actpos {a} ±{tol}"),
        }
    }
}

/// Faults every vendor's emulator has, by the effect the arm's user sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ArmFaultKind {
    /// The physical emergency stop is pressed: the arm stops and refuses motion until it is
    /// released (the fault cleared) and reset.
    Estop,
    /// The link between host and arm is cut both ways (Piper: every CAN frame lost; Realman:
    /// replies held back past the driver's timeout and the state push lost): calls time out
    /// and the realtime state stops until the fault clears.
    CommLoss,
}

impl ArmFaultKind {
    /// Every arm fault.
    pub const ALL: [Self; 2] = [Self::Estop, Self::CommLoss];

    /// The scenario name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Estop => "estop",
            Self::CommLoss => "comm_loss",
        }
    }
}

/// A validated arm fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArmFault(pub ArmFaultKind);

/// Error codes by name as a scenario writes them (`ARM_OUT_OF_RANGE`).
pub fn error_codes() -> Vec<(AbcErrorCode, &'static str)> {
    AbcErrorCode::ALL
        .into_iter()
        .filter(|c| *c != AbcErrorCode::Success)
        .map(|c| (c, c.name()))
        .collect()
}
