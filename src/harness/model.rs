//! Layer 2: a validated scenario. Every value here has been range-checked; units are in the
//! field names.

use std::path::PathBuf;
use std::time::Duration;

/// Number of joints of a Piper arm.
pub const PIPER_JOINTS: usize = 6;

/// A validated scenario, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Name (from `name:` or the file stem); names the output folder.
    pub name: String,
    /// The file it was loaded from.
    pub path: PathBuf,
    /// Free text.
    pub description: Option<String>,
    /// Tags; `vcan` marks scenarios that can run against a separate emulator process.
    pub tags: Vec<String>,
    /// Bus and devices.
    pub bench: Bench,
    /// What to record.
    pub record: Record,
    /// Faults scheduled by time or after a step.
    pub faults: Vec<ScheduledFault>,
    /// The steps, in order.
    pub steps: Vec<Step>,
}

impl Scenario {
    /// Whether the scenario carries `tag`.
    pub fn has_tag(&self, tag: &str) -> bool {
        self.tags.iter().any(|t| t == tag)
    }

    /// Why this scenario needs the in-process emulator and virtual bus (empty when it can run
    /// against a separate emulator process on a real interface).
    pub fn in_process_requirements(&self) -> Vec<String> {
        let mut needs = Vec::new();
        for fault in &self.faults {
            needs.push(format!(
                "scheduled fault `{}` (line {})",
                fault.fault.describe(),
                fault.line
            ));
        }
        for step in &self.steps {
            if let StepKind::Inject { fault, .. } = &step.kind {
                needs.push(format!(
                    "inject `{}` (line {})",
                    fault.describe(),
                    step.line
                ));
            }
            if let StepKind::ClearFaults { .. } = &step.kind {
                needs.push(format!("clear_faults (line {})", step.line));
            }
            if let StepKind::Action {
                action: Action::Robstride(a),
                ..
            } = &step.kind
            {
                if a.command.needs_emulator() {
                    needs.push(format!(
                        "robstride `{}` (line {})",
                        a.command.name(),
                        step.line
                    ));
                }
            }
        }
        for device in &self.bench.devices {
            let DeviceKind::Piper(settings) = &device.kind else {
                continue;
            };
            if !settings.obstacles.is_empty() {
                needs.push(format!("obstacles on `{}`", device.name));
            }
            if settings.initial_joints_deg.iter().any(|a| *a != 0.0) {
                needs.push(format!("initial_joints_deg on `{}`", device.name));
            }
            if settings.gripper_max_mm.is_some() || settings.collision_levels.is_some() {
                needs.push(format!(
                    "flash settings (gripper_max_mm, collision_levels) on `{}`",
                    device.name
                ));
            }
            if settings.urdf.is_some() {
                needs.push(format!("urdf on `{}`", device.name));
            }
        }
        needs
    }
}

/// The bus and the devices on it.
#[derive(Debug, Clone, PartialEq)]
pub struct Bench {
    /// Bit rate of the virtual bus.
    pub bitrate_bps: u32,
    /// Interface to use with `--iface` when the command line names none.
    pub interface: Option<String>,
    /// Devices, in file order (sorted by name: the file's mapping order is not kept).
    pub devices: Vec<DeviceSpec>,
}

/// One device on the bench.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceSpec {
    /// Its name in the scenario (also its node name on the virtual bus).
    pub name: String,
    /// What it is and its settings.
    pub kind: DeviceKind,
}

/// Device kinds with their settings.
#[derive(Debug, Clone, PartialEq)]
pub enum DeviceKind {
    /// An AgileX Piper arm.
    Piper(PiperSettings),
    /// A bus of RobStride actuators.
    Robstride(super::robstride::RobstrideSettings),
}

impl DeviceKind {
    /// The kind's name as written in scenarios.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Piper(_) => "piper",
            Self::Robstride(_) => "robstride",
        }
    }
}

/// Settings of an emulated Piper.
#[derive(Debug, Clone, PartialEq)]
pub struct PiperSettings {
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

/// What a run records.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Period of the state trace.
    pub sample_period: Duration,
    /// Signals in the trace.
    pub signals: Vec<Signal>,
    /// Write a candump log of the bus.
    pub candump: bool,
    /// Write a pcap of the bus.
    pub pcap: bool,
    /// Write an SVG plot.
    pub plot: bool,
}

/// A traced signal group.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Signal {
    /// Joint angles (0.1°).
    Joints,
    /// Joint speeds (0.1°/s).
    Speeds,
    /// Motor currents (0.01 A).
    Currents,
    /// Gripper stroke (0.1 mm).
    Gripper,
    /// Flange position (0.1 mm).
    Pose,
    /// Motor temperatures (1 °C).
    Temperatures,
    /// Arm status code and enable mask.
    Status,
}

impl Signal {
    /// Every signal and its scenario name.
    pub const ALL: [(Signal, &'static str); 7] = [
        (Signal::Joints, "joints"),
        (Signal::Speeds, "speeds"),
        (Signal::Currents, "currents"),
        (Signal::Gripper, "gripper"),
        (Signal::Pose, "pose"),
        (Signal::Temperatures, "temperatures"),
        (Signal::Status, "status"),
    ];
}

/// A fault and when to apply it.
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledFault {
    /// Line of the entry in the file.
    pub line: u64,
    /// When.
    pub trigger: FaultTrigger,
    /// Cleared after this long; `None` keeps it until the end (or `clear_faults`).
    pub duration: Option<Duration>,
    /// What.
    pub fault: FaultSpec,
}

/// When a scheduled fault starts.
#[derive(Debug, Clone, PartialEq)]
pub enum FaultTrigger {
    /// At this scenario time.
    At(Duration),
    /// This long after the step with this index (0-based) finished.
    AfterStep {
        /// Index of the step.
        step: usize,
        /// Extra delay.
        delay: Duration,
    },
}

/// A fault on a device's emulator or on the bus.
#[derive(Debug, Clone, PartialEq)]
pub enum FaultSpec {
    /// Applied by the device's emulator.
    Emulator {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The fault.
        fault: EmulatorFault,
    },
    /// Applied by the virtual bus.
    Bus(BusFault),
}

impl FaultSpec {
    /// Short description for logs and reports.
    pub fn describe(&self) -> String {
        match self {
            Self::Emulator { fault, .. } => fault.describe(),
            Self::Bus(fault) => fault.describe(),
        }
    }
}

/// Faults the firmware emulator produces (the device's view: flags on its feedback).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EmulatorFault {
    /// The master loses contact with a joint driver.
    CommLoss {
        /// Joint 1..=6.
        joint: u8,
    },
    /// Motor winding over-temperature.
    MotorOverTemp {
        /// Joint 1..=6.
        joint: u8,
        /// Forced temperature.
        temp_c: f64,
    },
    /// Driver over-temperature.
    DriverOverTemp {
        /// Joint 1..=6.
        joint: u8,
        /// Forced temperature.
        temp_c: f64,
    },
    /// Driver over-current protection (latched).
    OverCurrent {
        /// Joint 1..=6.
        joint: u8,
    },
    /// Supply sags (all joints).
    UnderVoltage {
        /// Bus voltage.
        voltage_v: f64,
    },
    /// Joint driver error (latched).
    DriverError {
        /// Joint 1..=6.
        joint: u8,
    },
    /// Stall protection (latched).
    Stall {
        /// Joint 1..=6.
        joint: u8,
    },
    /// A persistent external torque on a joint (collision by torque above the threshold).
    ExternalTorque {
        /// Joint 1..=6.
        joint: u8,
        /// Torque.
        torque_nm: f64,
    },
    /// Collision protection forced on a joint.
    Collision {
        /// Joint 1..=6.
        joint: u8,
    },
    /// Hardware emergency stop.
    Estop,
    /// NTC over-temperature.
    NtcOverTemp {
        /// Which board.
        board: NtcBoard,
    },
    /// Gripper sensor fault.
    GripperSensor,
    /// The teach (drag) button is pressed.
    TeachButton,
}

impl EmulatorFault {
    /// Short description.
    pub fn describe(&self) -> String {
        match self {
            Self::CommLoss { joint } => format!("comm_loss joint {joint}"),
            Self::MotorOverTemp { joint, temp_c } => {
                format!("motor_over_temp joint {joint} {temp_c} C")
            }
            Self::DriverOverTemp { joint, temp_c } => {
                format!("driver_over_temp joint {joint} {temp_c} C")
            }
            Self::OverCurrent { joint } => format!("over_current joint {joint}"),
            Self::UnderVoltage { voltage_v } => format!("under_voltage {voltage_v} V"),
            Self::DriverError { joint } => format!("driver_error joint {joint}"),
            Self::Stall { joint } => format!("stall joint {joint}"),
            Self::ExternalTorque { joint, torque_nm } => {
                format!("external_torque joint {joint} {torque_nm} Nm")
            }
            Self::Collision { joint } => format!("collision joint {joint}"),
            Self::Estop => "estop".to_owned(),
            Self::NtcOverTemp {
                board: NtcBoard::Main,
            } => "ntc_over_temp main".to_owned(),
            Self::NtcOverTemp {
                board: NtcBoard::BrakeResistor,
            } => "ntc_over_temp brake_resistor".to_owned(),
            Self::GripperSensor => "gripper_sensor_fault".to_owned(),
            Self::TeachButton => "teach_button".to_owned(),
        }
    }
}

/// Boards with an NTC sensor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NtcBoard {
    /// Main board (arm status 0x0E).
    Main,
    /// Brake resistor (arm status 0x0F).
    BrakeResistor,
}

/// Which frames a bus fault hits.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FrameSelector {
    /// Every frame.
    All,
    /// One identifier.
    Id(u32),
    /// Frames sent by this node (device name, or `host` for the driver).
    Node(String),
}

impl FrameSelector {
    fn describe(&self) -> String {
        match self {
            Self::All => "all frames".to_owned(),
            Self::Id(id) => format!("id 0x{id:03X}"),
            Self::Node(node) => format!("node {node}"),
        }
    }
}

/// Faults on the virtual bus.
#[derive(Debug, Clone, PartialEq)]
pub enum BusFault {
    /// Drop frames (all, or with a seeded probability).
    Drop {
        /// Which frames.
        frames: FrameSelector,
        /// Probability and seed, `None` for every frame.
        probability: Option<(f64, u64)>,
    },
    /// Delay frames.
    Delay {
        /// Which frames.
        frames: FrameSelector,
        /// How long.
        delay: Duration,
    },
    /// Corrupt frames (CRC error: nobody receives them).
    Corrupt {
        /// Which frames.
        frames: FrameSelector,
    },
    /// Deliver frames twice.
    Duplicate {
        /// Which frames.
        frames: FrameSelector,
    },
    /// Silence a node: its frames never reach the wire.
    Silence {
        /// Node name.
        node: String,
    },
    /// Put a node into bus-off (needs a duration).
    BusOff {
        /// Node name.
        node: String,
    },
}

impl BusFault {
    /// Short description.
    pub fn describe(&self) -> String {
        match self {
            Self::Drop {
                frames,
                probability: None,
            } => format!("drop {}", frames.describe()),
            Self::Drop {
                frames,
                probability: Some((p, seed)),
            } => format!("drop {} p={p} seed={seed}", frames.describe()),
            Self::Delay { frames, delay } => {
                format!("delay {} by {} ms", frames.describe(), delay.as_millis())
            }
            Self::Corrupt { frames } => format!("corrupt {}", frames.describe()),
            Self::Duplicate { frames } => format!("duplicate {}", frames.describe()),
            Self::Silence { node } => format!("silence node {node}"),
            Self::BusOff { node } => format!("bus_off node {node}"),
        }
    }
}

/// One step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// 0-based index.
    pub index: usize,
    /// Line in the file.
    pub line: u64,
    /// Optional label (`id:`), referenced by `after:` in the fault schedule.
    pub id: Option<String>,
    /// Short text for reports (`move_j`, `wait_until`...).
    pub label: String,
    /// What it does.
    pub kind: StepKind,
}

/// What a step does.
#[derive(Debug, Clone, PartialEq)]
pub enum StepKind {
    /// Let time pass.
    Wait(Duration),
    /// A driver action on a device.
    Action {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The action.
        action: Action,
        /// Overrides the driver's default timeout.
        timeout: Option<Duration>,
        /// The action must fail with this error class instead of succeeding.
        expect_error: Option<ErrorClass>,
    },
    /// Conditions that must hold now (or throughout `hold`).
    Expect {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The conditions.
        checks: Vec<Check>,
        /// Must hold for this long (sampled every millisecond of scenario time).
        hold: Option<Duration>,
    },
    /// Poll until the conditions hold, at most `timeout`.
    WaitUntil {
        /// Index into [`Bench::devices`].
        device: usize,
        /// The conditions.
        checks: Vec<Check>,
        /// Give up after this long.
        timeout: Duration,
    },
    /// Inject a fault now.
    Inject {
        /// The fault.
        fault: FaultSpec,
        /// Cleared after this long.
        duration: Option<Duration>,
    },
    /// Clear every injected fault (emulator and bus).
    ClearFaults {
        /// Index into [`Bench::devices`].
        device: usize,
    },
}

/// Classes of driver errors a step can expect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorClass {
    /// No (confirming) reply in time.
    Timeout,
    /// The device refused or reported an error status.
    Rejected,
    /// The bus failed (bus-off, closed...).
    Bus,
    /// An argument the driver refused before sending.
    InvalidArgument,
    /// Any error at all.
    Any,
}

impl ErrorClass {
    /// Names as written in scenarios.
    pub const NAMES: [(ErrorClass, &'static str); 5] = [
        (ErrorClass::Timeout, "timeout"),
        (ErrorClass::Rejected, "rejected"),
        (ErrorClass::Bus, "bus"),
        (ErrorClass::InvalidArgument, "invalid_argument"),
        (ErrorClass::Any, "any"),
    ];

    /// The scenario name.
    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(class, _)| *class == self)
            .map_or("any", |(_, name)| name)
    }
}

/// A Cartesian pose of the flange.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// X, Y, Z in millimetres.
    pub position_mm: [f64; 3],
    /// RX, RY, RZ in degrees.
    pub orientation_deg: [f64; 3],
}

/// Device actions.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Actions on a Piper.
    Piper(PiperAction),
    /// A command to a RobStride motor (or its emulator).
    Robstride(super::robstride::RobstrideAction),
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

/// An expected numeric reply value with its tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Near {
    /// Expected value.
    pub value: f64,
    /// Allowed deviation.
    pub tolerance: f64,
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
    },
    /// MOVE P to a pose.
    MoveP {
        /// Target.
        pose: Pose,
        /// Speed percentage.
        speed_pct: u8,
    },
    /// MOVE L to a pose.
    MoveL {
        /// Target.
        pose: Pose,
        /// Speed percentage.
        speed_pct: u8,
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
    /// A condition on one RobStride motor.
    Motor {
        /// CAN ID.
        motor: u8,
        /// The condition.
        cond: super::robstride::MotorCond,
    },
}
