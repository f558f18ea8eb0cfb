//! Typed values carried by requests, replies and pushed state.

/// A tool pose: position in metres and orientation as intrinsic Z-Y-X Euler angles
/// (R = Rz(rz)·Ry(ry)·Rx(rx)), in the current work frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// x, y, z in metres.
    pub position_m: [f64; 3],
    /// rx, ry, rz in radians.
    pub euler_rad: [f64; 3],
}

/// A pose with a unit quaternion instead of Euler angles (passthrough `pose_quat`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct QuatPose {
    /// x, y, z in metres.
    pub position_m: [f64; 3],
    /// w, x, y, z.
    pub quaternion_wxyz: [f64; 4],
}

/// Which device an arrival event is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Device {
    /// The arm joints (0).
    Arm,
    /// The gripper (1).
    Gripper,
    /// The dexterous hand (2).
    Hand,
    /// The lift (3).
    Lift,
    /// The expansion joint (4).
    Expansion,
    /// A number this driver does not know.
    Unknown(i64),
}

impl Device {
    /// From the wire number.
    pub fn from_wire(v: i64) -> Self {
        match v {
            0 => Self::Arm,
            1 => Self::Gripper,
            2 => Self::Hand,
            3 => Self::Lift,
            4 => Self::Expansion,
            other => Self::Unknown(other),
        }
    }
}

/// `trajectory_connect` of a planned move: run now, or queue with the next command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Connect {
    /// 0: plan (with anything queued) and run.
    #[default]
    Start,
    /// 1: queue; nothing moves until a [`Connect::Start`] command arrives.
    Queue,
}

impl Connect {
    /// The wire value.
    pub fn wire(self) -> u8 {
        match self {
            Self::Start => 0,
            Self::Queue => 1,
        }
    }
}

/// The `current_trajectory_state` arrival event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Arrival {
    /// `trajectory_state`: false = the motion failed or was aborted.
    pub ok: bool,
    /// Which device arrived.
    pub device: Device,
    /// `trajectory_connect` 1: one connected segment done, more follow. Missing in some
    /// firmware's gripper/hand events; read as 0 then.
    pub more_follow: bool,
}

/// Axis for Cartesian step and jog commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// x (position) or rx (orientation).
    X,
    /// y or ry.
    Y,
    /// z or rz.
    Z,
}

impl Axis {
    pub(crate) fn letter(self) -> &'static str {
        match self {
            Self::X => "x",
            Self::Y => "y",
            Self::Z => "z",
        }
    }
}

/// Jog direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Positive ("pos").
    Positive,
    /// Negative ("neg").
    Negative,
}

impl Direction {
    pub(crate) fn wire(self) -> &'static str {
        match self {
            Self::Positive => "pos",
            Self::Negative => "neg",
        }
    }
}

/// Passthrough smoothing (`trajectory_mode` + `radio`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Smoothing {
    /// 0: raw, no smoothing.
    #[default]
    Raw,
    /// 1: curve fitting with a smoothing level 0..=100.
    CurveFit(u16),
    /// 2: filtering with a level 0..=1000.
    Filter(u16),
}

/// `arm_current_status` strings of the realtime push.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ArmStatus {
    /// `idle`.
    Idle,
    /// `move_L`.
    MoveL,
    /// `move_J`.
    MoveJ,
    /// `move_C`.
    MoveC,
    /// `move_S`.
    MoveS,
    /// `move_through_joint`.
    MoveThroughJoint,
    /// `move_through_pose`.
    MoveThroughPose,
    /// `move_through_force_pose`.
    MoveThroughForcePose,
    /// `move_through_current`.
    MoveThroughCurrent,
    /// `stop`.
    Stop,
    /// `slow_stop`.
    SlowStop,
    /// `pause`.
    Pause,
    /// `current_drag`.
    CurrentDrag,
    /// `sensor_drag`.
    SensorDrag,
    /// `tech_demonstration`.
    TeachDemonstration,
    /// `trajectory_reproducton` (sic, as on the wire).
    TrajectoryReproduction,
    /// `move_init_position`.
    MoveInitPosition,
    /// `movev_canfd`.
    MovevCanfd,
    /// A string a newer controller may send.
    Unknown(String),
}

impl ArmStatus {
    /// From the wire string.
    pub fn from_wire(s: &str) -> Self {
        match s {
            "idle" => Self::Idle,
            "move_L" => Self::MoveL,
            "move_J" => Self::MoveJ,
            "move_C" => Self::MoveC,
            "move_S" => Self::MoveS,
            "move_through_joint" => Self::MoveThroughJoint,
            "move_through_pose" => Self::MoveThroughPose,
            "move_through_force_pose" => Self::MoveThroughForcePose,
            "move_through_current" => Self::MoveThroughCurrent,
            "stop" => Self::Stop,
            "slow_stop" => Self::SlowStop,
            "pause" => Self::Pause,
            "current_drag" => Self::CurrentDrag,
            "sensor_drag" => Self::SensorDrag,
            "tech_demonstration" => Self::TeachDemonstration,
            "trajectory_reproducton" => Self::TrajectoryReproduction,
            "move_init_position" => Self::MoveInitPosition,
            "movev_canfd" => Self::MovevCanfd,
            other => Self::Unknown(other.to_string()),
        }
    }
}

/// The kind of trajectory `get_arm_current_trajectory` reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TrajectoryKind {
    /// `none`: at rest.
    None,
    /// `movej`.
    MoveJ,
    /// `movel`.
    MoveL,
    /// `movec`.
    MoveC,
    /// `moves`.
    MoveS,
    /// Any other string (teach replay, blends, newer firmware).
    Unknown(String),
}

impl TrajectoryKind {
    /// From the wire string.
    pub fn from_wire(s: &str) -> Self {
        match s {
            "none" => Self::None,
            "movej" => Self::MoveJ,
            "movel" => Self::MoveL,
            "movec" => Self::MoveC,
            "moves" => Self::MoveS,
            other => Self::Unknown(other.to_string()),
        }
    }
}

macro_rules! controller_errors {
    ($( $code:literal => $name:ident, $doc:literal; )*) => {
        /// System / arm error codes (`err[]`, `arm_err`, `sys_err`; docs/protocols/realman.md §12).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum ControllerError {
            $( #[doc = $doc] $name, )*
            /// A code this driver does not know.
            Unknown(u32),
        }

        impl ControllerError {
            /// From the wire code (0 is "no error" and is not represented).
            pub fn from_code(code: u32) -> Self {
                match code {
                    $( $code => Self::$name, )*
                    other => Self::Unknown(other),
                }
            }

            /// The wire code.
            pub fn code(self) -> u32 {
                match self {
                    $( Self::$name => $code, )*
                    Self::Unknown(c) => c,
                }
            }
        }
    };
}

controller_errors! {
    0x1001 => JointCommsAbnormal, "Joint communication abnormal (severe).";
    0x1002 => TargetBeyondJointLimit, "Target angle beyond the joint limit.";
    0x1003 => Unreachable, "Target unreachable or singular.";
    0x1004 => KernelCommsError, "Real-time kernel communication error (severe).";
    0x1005 => JointBusError, "Joint bus error (severe).";
    0x1006 => PlanningKernelError, "Planning-layer kernel error (severe).";
    0x1007 => JointOverspeed, "Joint overspeed.";
    0x1008 => ToolBoardUnreachable, "Tool interface board unreachable (severe).";
    0x1009 => OverSpeedLimit, "Over the speed limit.";
    0x100A => OverAccelerationLimit, "Over the acceleration limit.";
    0x100B => BrakeNotReleased, "Joint brake not released.";
    0x100C => DragTeachOverspeed, "Overspeed during drag teaching.";
    0x100D => Collision, "Collision detected.";
    0x100E => NoSuchWorkFrame, "No such work frame.";
    0x100F => NoSuchToolFrame, "No such tool frame.";
    0x1010 => JointDisabled, "Joint enable lost.";
    0x1011 => ArcPlanningError, "Arc planning error.";
    0x1012 => SelfCollision, "Self-collision.";
    0x1013 => ElectronicFence, "Electronic fence hit.";
    0x1014 => JointSoftLimit, "Joint soft limit exceeded.";
    0x2001 => GripperFault, "Gripper fault.";
    0x2002 => HandFault, "Dexterous hand fault.";
    0x2003 => SixAxisForceFault, "Six-axis force module fault.";
    0x2004 => OneAxisForceFault, "One-axis force module fault.";
    0x2005 => OutputCurrentAbnormal, "Output current abnormal.";
    0x5003 => ControllerOverTemperature, "Controller over-temperature.";
    0x5005 => OverCurrent, "Over-current.";
    0x5006 => UnderCurrent, "Under-current.";
    0x5007 => OverVoltage, "Over-voltage.";
    0x5008 => UnderVoltage, "Under-voltage.";
    0x5009 => KernelCommsError2, "Real-time kernel communication error (controller side).";
}

/// Error codes from a list, dropping zeros (0 = no error).
pub fn controller_errors(codes: impl IntoIterator<Item = u32>) -> Vec<ControllerError> {
    codes
        .into_iter()
        .filter(|&c| c != 0)
        .map(ControllerError::from_code)
        .collect()
}

/// Joint error bits (`err_flag`, `joint_err_code`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct JointErrorFlags(pub u16);

impl JointErrorFlags {
    /// FOC error.
    pub const FOC: u16 = 0x0001;
    /// Over-voltage.
    pub const OVER_VOLTAGE: u16 = 0x0002;
    /// Under-voltage.
    pub const UNDER_VOLTAGE: u16 = 0x0004;
    /// Over-temperature.
    pub const OVER_TEMPERATURE: u16 = 0x0008;
    /// Start-up failure.
    pub const STARTUP: u16 = 0x0010;
    /// Encoder error.
    pub const ENCODER: u16 = 0x0020;
    /// Over-current.
    pub const OVER_CURRENT: u16 = 0x0040;
    /// Software error.
    pub const SOFTWARE: u16 = 0x0080;
    /// Temperature sensor error.
    pub const TEMPERATURE_SENSOR: u16 = 0x0100;
    /// Position over limit.
    pub const POSITION_LIMIT: u16 = 0x0200;
    /// Illegal joint ID.
    pub const ILLEGAL_ID: u16 = 0x0400;
    /// Position tracking error.
    pub const POSITION_TRACKING: u16 = 0x0800;
    /// Current sensing error.
    pub const CURRENT_SENSING: u16 = 0x1000;
    /// Brake release failed.
    pub const BRAKE_RELEASE: u16 = 0x2000;
    /// Position-command step warning.
    pub const STEP_WARNING: u16 = 0x4000;
    /// Multi-turn count lost.
    pub const MULTI_TURN_LOST: u16 = 0x8000;

    /// True when any bit is set.
    pub fn any(self) -> bool {
        self.0 != 0
    }

    /// True when `bit` (one of the constants) is set.
    pub fn contains(self, bit: u16) -> bool {
        self.0 & bit == bit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_codes_round_trip_and_unknown() {
        assert_eq!(
            ControllerError::from_code(4098),
            ControllerError::TargetBeyondJointLimit
        );
        assert_eq!(ControllerError::from_code(0x100D).code(), 0x100D);
        assert_eq!(
            ControllerError::from_code(0x7777),
            ControllerError::Unknown(0x7777)
        );
        assert_eq!(
            controller_errors([0, 4109]),
            vec![ControllerError::Collision]
        );
    }

    #[test]
    fn status_strings() {
        assert_eq!(ArmStatus::from_wire("move_J"), ArmStatus::MoveJ);
        assert_eq!(
            ArmStatus::from_wire("zero_g"),
            ArmStatus::Unknown("zero_g".into())
        );
        assert_eq!(Device::from_wire(2), Device::Hand);
        assert_eq!(Device::from_wire(9), Device::Unknown(9));
    }
}
