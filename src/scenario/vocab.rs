//! The vocabulary every device kind and the harness share: which signals a scenario traces,
//! which classes of driver error a step may expect, and a value with its tolerance.

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
    /// Motor torques (devices that report torque).
    Torques,
    /// Arm status code and enable mask.
    Status,
}

impl Signal {
    /// Every signal and its scenario name.
    pub const ALL: [(Signal, &'static str); 8] = [
        (Signal::Joints, "joints"),
        (Signal::Speeds, "speeds"),
        (Signal::Currents, "currents"),
        (Signal::Gripper, "gripper"),
        (Signal::Pose, "pose"),
        (Signal::Temperatures, "temperatures"),
        (Signal::Torques, "torques"),
        (Signal::Status, "status"),
    ];
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

/// An expected numeric reply value with its tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Near {
    /// Expected value.
    pub value: f64,
    /// Allowed deviation.
    pub tolerance: f64,
}

/// A device step as its kind validated it: which device, the kind's own action, and the two
/// keys every device step shares. The harness places it in the scenario (as
/// `StepKind::Action`), so that a kind never builds the harness's step type.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceStep<A> {
    /// Index of the device on the bench.
    pub device: usize,
    /// The kind's action.
    pub action: A,
    /// Overrides the driver's default timeout (`timeout_ms`).
    pub timeout: Option<std::time::Duration>,
    /// The action must fail with this error class (`expect_error`).
    pub expect_error: Option<ErrorClass>,
}
