//! The validated `actuator_group` vocabulary.

use std::time::Duration;

use sim::actuator::ActuatorConfig;
use sim::fault_args::FaultArgs;
use sim::robot::RobotConfig;

/// One actuator: the joint it drives and its motor.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupActuator {
    /// The joint's name (how steps, checks, faults and trace columns address it).
    pub joint: String,
    /// The actuator: its kind, model and CAN ID (and, on a bench without a robot, the
    /// RobStride rig its shaft drives).
    pub actuator: ActuatorConfig,
    /// Index of its bus in [`GroupSettings::buses`].
    pub bus: usize,
}

/// A group's settings: its actuators in file order, on one bus or, for a robot, on its buses.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupSettings {
    /// The actuators.
    pub actuators: Vec<GroupActuator>,
    /// The buses' names (`bench` for a group without a robot: the bench's own bus).
    pub buses: Vec<String>,
    /// The robot the actuators belong to (one physics world), when the group is one.
    pub robot: Option<RobotConfig>,
}

/// A joint target: the actuator's index in [`GroupSettings::actuators`] and an angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointTarget {
    /// Index of the actuator.
    pub actuator: usize,
    /// Angle (rad).
    pub angle_rad: f64,
}

/// What a `group:` step does.
#[derive(Debug, Clone, PartialEq)]
pub enum GroupAction {
    /// Enable every actuator (each holds where it is) and turn on their active reports.
    Enable,
    /// Disable every actuator (torque off).
    Disable,
    /// Send each listed joint an operation-control (MIT) command to hold `angle_rad`.
    Hold {
        /// The joints and their angles.
        targets: Vec<JointTarget>,
        /// Stiffness (N·m/rad).
        kp: f64,
        /// Damping (N·m·s/rad).
        kd: f64,
        /// Send the command again at this period, in the background, until the joint's next
        /// `hold`, `enable` or `disable` (a host's control loop; what a CAN watchdog wants).
        every: Option<Duration>,
    },
    /// Switch every actuator to a run mode (disable, write run_mode, read it back, enable).
    Mode(GroupMode),
    /// Cyclic synchronous position (run mode CSP): each listed joint to its angle at most at
    /// `speed_rad_s` (limit_spd, then loc_ref).
    Move {
        /// The joints and their angles.
        targets: Vec<JointTarget>,
        /// Speed limit (rad/s).
        speed_rad_s: f64,
    },
    /// The robot's gantry lets go of its base (the bench's doing, not a frame on the bus):
    /// from then on the robot stands on its actuators or falls.
    ReleaseGantry,
    /// Arm every actuator's CAN watchdog (canTimeout): an actuator that receives no command
    /// for `window` resets (torque off).
    Watchdog {
        /// The window.
        window: Duration,
    },
}

/// The run modes a group switches between.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GroupMode {
    /// Operation control (MIT): `hold`.
    Mit,
    /// Cyclic synchronous position: `move`.
    Csp,
}

/// A condition on the group as the driver sees it.
#[derive(Debug, Clone, PartialEq)]
pub enum GroupCheck {
    /// Each listed joint within `tolerance_rad` of its angle.
    Joints {
        /// The joints, their names (for reports) and angles.
        targets: Vec<(String, JointTarget)>,
        /// Allowed deviation (rad).
        tolerance_rad: f64,
    },
    /// Exactly these joints' actuators are enabled (running), the others not.
    EnabledJoints(Vec<String>),
    /// A robot's root link (a humanoid's pelvis) within `tolerance_m` of `height_m` above the
    /// ground: the emulator's truth, as a motion-capture system would see it (no actuator
    /// reports it).
    BaseHeight {
        /// Height (m).
        height_m: f64,
        /// Allowed deviation (m).
        tolerance_m: f64,
    },
}

/// A fault of an actuator's kind (its table) on one actuator.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupFault {
    /// The joint's name.
    pub joint: String,
    /// Index of the actuator in [`GroupSettings::actuators`].
    pub actuator: usize,
    /// The fault's name in the kind's table.
    pub fault: String,
    /// Its values (`counts` of an encoder glitch), checked by the kind at load.
    pub args: FaultArgs,
    /// How it shows applied (`encoder_glitch 100 counts`).
    pub label: String,
}

impl GroupCheck {
    /// What the condition wants, for reports.
    pub fn describe(&self) -> String {
        match self {
            Self::Joints {
                targets,
                tolerance_rad,
            } => targets
                .iter()
                .map(|(name, t)| format!("{name} {:.3} ±{tolerance_rad} rad", t.angle_rad))
                .collect::<Vec<_>>()
                .join(", "),
            Self::EnabledJoints(joints) => format!("enabled: [{}]", joints.join(", ")),
            Self::BaseHeight {
                height_m,
                tolerance_m,
            } => format!("base height {height_m:.3} ±{tolerance_m} m"),
        }
    }
}
