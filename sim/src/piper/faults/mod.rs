//! Faults the harness can trigger at run time: [`PiperFault`] with its values, [`FaultKind`] the
//! table of kinds. This is the one description of the Piper's faults: [`FaultKind::name`] is a
//! fault's name in scenario files, [`FaultKind::params`] its parameters and
//! [`FaultKind::description`] what it does on the wire and what clears it; [`FaultKind::build`]
//! (and [`build_fault`] by name) is the one way a front end (scenario files, the web view,
//! Python) turns a name and [`FaultArgs`](crate::fault_args::FaultArgs) into a [`PiperFault`].
//! What a fault does to the firmware is `firmware::protections`.

mod build;
mod target;

pub use build::build_fault;
pub use target::fault_table;

/// A fault the harness injects into a running emulator. Joints are numbered 1–6 as on the wire.
///
/// This type, with [`FaultKind`], is the one description of the Piper's faults: scenario files,
/// reports and plots use [`FaultKind::name`] and this type's `Display`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PiperFault {
    /// See [`FaultKind::CommLoss`].
    CommLoss {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`FaultKind::MotorOverTemp`].
    MotorOverTemp {
        /// Joint 1–6.
        joint: u8,
        /// Forced winding temperature, °C.
        temp_c: f64,
    },
    /// See [`FaultKind::DriverOverTemp`].
    DriverOverTemp {
        /// Joint 1–6.
        joint: u8,
        /// Forced driver temperature, °C.
        temp_c: f64,
    },
    /// See [`FaultKind::OverCurrent`].
    OverCurrent {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`FaultKind::UnderVoltage`].
    UnderVoltage {
        /// Bus voltage, V.
        voltage_v: f64,
    },
    /// See [`FaultKind::DriverError`].
    DriverError {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`FaultKind::Stall`].
    Stall {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`FaultKind::ExternalTorque`].
    ExternalTorque {
        /// Joint 1–6.
        joint: u8,
        /// Torque, N·m.
        torque_nm: f64,
    },
    /// See [`FaultKind::Collision`].
    Collision {
        /// Joint 1–6.
        joint: u8,
    },
    /// See [`FaultKind::Estop`].
    Estop,
    /// See [`FaultKind::NtcOverTemp`].
    NtcOverTemp {
        /// Which board's sensor.
        board: NtcBoard,
    },
    /// See [`FaultKind::GripperSensorFault`].
    GripperSensorFault,
    /// See [`FaultKind::TeachButton`].
    TeachButton,
}

/// Boards with an NTC temperature sensor. Its name (scenario files, reports, the web view,
/// Python) is its variant's in snake_case.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[strum(serialize_all = "snake_case")]
pub enum NtcBoard {
    /// Main-control board (arm status 0x0E).
    Main,
    /// Brake resistor (arm status 0x0F).
    BrakeResistor,
}

impl NtcBoard {
    /// Both boards.
    pub const ALL: [NtcBoard; 2] = [NtcBoard::Main, NtcBoard::BrakeResistor];

    /// The board's name in scenario files and reports.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The board with this [`name`](NtcBoard::name).
    pub fn from_name(name: &str) -> Option<NtcBoard> {
        name.parse().ok()
    }
}

/// The kinds of [`PiperFault`], without their values: one row per fault of the table above.
/// Its name (scenario files, logs, reports, the web view, Python) is its variant's in
/// snake_case.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[strum(serialize_all = "snake_case")]
pub enum FaultKind {
    /// The master loses contact with one joint driver.
    CommLoss,
    /// Motor winding over-temperature (temperature forced).
    MotorOverTemp,
    /// Driver over-temperature (temperature forced).
    DriverOverTemp,
    /// Driver over-current protection trips (latched).
    OverCurrent,
    /// Supply voltage sags (all joints).
    UnderVoltage,
    /// Generic driver error (latched).
    DriverError,
    /// Stall protection trips (latched).
    Stall,
    /// A persistent external torque on a joint, applied in the physics world.
    ExternalTorque,
    /// Collision protection triggered on a joint without a physical cause.
    Collision,
    /// The physical e-stop.
    Estop,
    /// NTC over-temperature of the main-control board or the brake resistor.
    NtcOverTemp,
    /// Gripper sensor fault.
    GripperSensorFault,
    /// The teach (drag) button on the arm is pressed.
    TeachButton,
}

/// One parameter of a fault kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultParam {
    /// Its name in scenario files (units in the name).
    pub name: &'static str,
    /// What it sets.
    pub description: &'static str,
    /// Whether a scenario must give it.
    pub required: bool,
    /// The numeric value when omitted (`None` for required and non-numeric parameters).
    pub default: Option<f64>,
    /// The smallest and largest value accepted, inclusive (`None` for non-numeric
    /// parameters). Every way of building a fault (scenario files, the web view, Python, the
    /// emulator's own `inject`) checks values against this through [`FaultParam::check`], so
    /// a physically absurd value is refused with a message instead of turning the physics into
    /// NaN.
    pub range: Option<(f64, f64)>,
    /// The words a word parameter accepts (empty for numeric parameters); when it is omitted
    /// the fault takes the first.
    pub words: &'static [&'static str],
}

impl FaultParam {
    /// `value` if it is finite and within [`FaultParam::range`], else why not.
    pub fn check(&self, value: f64) -> Result<f64, FaultError> {
        if !value.is_finite() {
            return Err(FaultError::NotFinite {
                param: self.name,
                value,
            });
        }
        match self.range {
            Some((min, max)) if !(min..=max).contains(&value) => Err(FaultError::OutOfRange {
                param: self.name,
                value,
                min,
                max,
            }),
            _ => Ok(value),
        }
    }
}

/// Largest external torque, N·m: ten times the peak torque of the Piper's largest joint motor
/// (32 N·m on joints 1–3, `urdf/piper.urdf`). A push well past what the motors can answer
/// still trips collision protection and stall tests; a bigger one is not a disturbance any
/// test can mean, and far bigger ones (1e308) overflow the f32 physics into NaN.
const MAX_EXTERNAL_TORQUE_NM: f64 = 320.0;

/// Forced temperatures, °C: from −40 °C (the coldest rating of industrial electronics) to
/// 200 °C (past class-H winding insulation, 180 °C, where a motor is destroyed). Every
/// protection threshold (80 °C driver, 90 °C motor) lies well inside.
const TEMP_RANGE_C: (f64, f64) = (-40.0, 200.0);

/// Bus voltage of `under_voltage`, V: from 0 (supply gone) to 60 V, a little above the 48 V
/// supply. The fault models a sag; no supply the arm runs on reads higher.
const VOLTAGE_RANGE_V: (f64, f64) = (0.0, 60.0);

/// The joint a fault acts on.
const JOINT: FaultParam = FaultParam {
    name: "joint",
    description: "joint 1–6",
    required: true,
    default: None,
    range: Some((1.0, 6.0)),
    words: &[],
};

/// Forced temperature of the over-temperature faults, °C (the default is above every
/// threshold).
const TEMP_C: FaultParam = FaultParam {
    name: "temp_c",
    description: "forced temperature, °C",
    required: false,
    default: Some(90.0),
    range: Some(TEMP_RANGE_C),
    words: &[],
};

/// Bus voltage of `under_voltage`, V (the default is below the drivers' 20 V threshold).
const VOLTAGE_V: FaultParam = FaultParam {
    name: "voltage_v",
    description: "bus voltage, V (nominal 48 V; drivers trip below 20 V)",
    required: false,
    default: Some(18.0),
    range: Some(VOLTAGE_RANGE_V),
    words: &[],
};

/// Torque of `external_torque`, N·m.
const TORQUE_NM: FaultParam = FaultParam {
    name: "torque_nm",
    description: "torque, N·m (at most 320 N·m either way)",
    required: true,
    default: None,
    range: Some((-MAX_EXTERNAL_TORQUE_NM, MAX_EXTERNAL_TORQUE_NM)),
    words: &[],
};

/// The board of `ntc_over_temp`: the names of [`NtcBoard`], the main board first (the
/// default).
const BOARD: FaultParam = FaultParam {
    name: "board",
    description: "`main` (default) or `brake_resistor`",
    required: false,
    default: None,
    range: None,
    words: &["main", "brake_resistor"],
};

impl FaultKind {
    /// Every fault the emulator can inject.
    pub const ALL: [FaultKind; 13] = [
        FaultKind::CommLoss,
        FaultKind::MotorOverTemp,
        FaultKind::DriverOverTemp,
        FaultKind::OverCurrent,
        FaultKind::UnderVoltage,
        FaultKind::DriverError,
        FaultKind::Stall,
        FaultKind::ExternalTorque,
        FaultKind::Collision,
        FaultKind::Estop,
        FaultKind::NtcOverTemp,
        FaultKind::GripperSensorFault,
        FaultKind::TeachButton,
    ];

    /// The fault's name in scenario files, logs and reports.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The kind with this [`name`](FaultKind::name).
    pub fn from_name(name: &str) -> Option<FaultKind> {
        name.parse().ok()
    }

    /// Its parameters, in the order `Display` prints them.
    pub fn params(self) -> &'static [FaultParam] {
        match self {
            FaultKind::CommLoss
            | FaultKind::OverCurrent
            | FaultKind::DriverError
            | FaultKind::Stall
            | FaultKind::Collision => &[JOINT],
            FaultKind::MotorOverTemp | FaultKind::DriverOverTemp => &[JOINT, TEMP_C],
            FaultKind::UnderVoltage => &[VOLTAGE_V],
            FaultKind::ExternalTorque => &[JOINT, TORQUE_NM],
            FaultKind::NtcOverTemp => &[BOARD],
            FaultKind::Estop | FaultKind::GripperSensorFault | FaultKind::TeachButton => &[],
        }
    }

    /// The parameter called `name`, if this kind takes one.
    pub fn param(self, name: &str) -> Option<&'static FaultParam> {
        self.params().iter().find(|p| p.name == name)
    }

    /// Whether the fault can be written without arguments (no parameter is required).
    pub fn bare_ok(self) -> bool {
        self.params().iter().all(|p| !p.required)
    }

    /// One line on what the fault does on the wire (spec §4) and what clears it; `clear` (the
    /// harness removing the cause) always does.
    pub fn description(self) -> &'static str {
        match self {
            FaultKind::CommLoss => {
                "master loses a joint driver: 0x2A1 byte 7 bit, arm status 0x05, its 0x25x/0x26x stop, motor off"
            }
            FaultKind::MotorOverTemp => {
                "winding temperature forced high: 0x26x bit 1, driver disables, arm status 0x09; re-enable after clear"
            }
            FaultKind::DriverOverTemp => {
                "driver temperature forced high: 0x26x bit 3, driver disables, arm status 0x09; re-enable after clear"
            }
            FaultKind::OverCurrent => {
                "latched 0x26x bit 2, driver disables, arm status 0x09; 0x475 clear error or 0x150 reset"
            }
            FaultKind::UnderVoltage => {
                "bus voltage in 0x26x drops, bit 0 on every joint, drivers disable, arm status 0x09; re-enable after clear"
            }
            FaultKind::DriverError => {
                "latched 0x26x bit 5, driver disables, arm status 0x09; 0x475 clear error or 0x150 reset"
            }
            FaultKind::Stall => {
                "latched 0x26x bit 7, driver disables, arm status 0x09; 0x475 clear error or 0x150 reset"
            }
            FaultKind::ExternalTorque => {
                "torque in the physics world; above the collision threshold arm status 0x07 and 0x26x bit 4, latched until 0x150 reset or 0x475"
            }
            FaultKind::Collision => {
                "forced collision latch: 0x26x bit 4, arm status 0x07; 0x150 reset or 0x475 clear error"
            }
            FaultKind::Estop => "physical e-stop: damping mode, arm status 0x01; 0x150 reset",
            FaultKind::NtcOverTemp => {
                "board NTC over-temperature: arm status 0x0E (main) / 0x0F (brake resistor), motion stops"
            }
            FaultKind::GripperSensorFault => "0x2A8 bit 4, the gripper stops",
            FaultKind::TeachButton => {
                "ctrl_mode 0x02, arm compliant (gravity compensation); clear presses it again (standby)"
            }
        }
    }
}

impl PiperFault {
    /// Its kind.
    pub fn kind(&self) -> FaultKind {
        match self {
            Self::CommLoss { .. } => FaultKind::CommLoss,
            Self::MotorOverTemp { .. } => FaultKind::MotorOverTemp,
            Self::DriverOverTemp { .. } => FaultKind::DriverOverTemp,
            Self::OverCurrent { .. } => FaultKind::OverCurrent,
            Self::UnderVoltage { .. } => FaultKind::UnderVoltage,
            Self::DriverError { .. } => FaultKind::DriverError,
            Self::Stall { .. } => FaultKind::Stall,
            Self::ExternalTorque { .. } => FaultKind::ExternalTorque,
            Self::Collision { .. } => FaultKind::Collision,
            Self::Estop => FaultKind::Estop,
            Self::NtcOverTemp { .. } => FaultKind::NtcOverTemp,
            Self::GripperSensorFault => FaultKind::GripperSensorFault,
            Self::TeachButton => FaultKind::TeachButton,
        }
    }

    /// The joint it acts on, for per-joint faults.
    pub fn joint(&self) -> Option<u8> {
        match *self {
            Self::CommLoss { joint }
            | Self::MotorOverTemp { joint, .. }
            | Self::DriverOverTemp { joint, .. }
            | Self::OverCurrent { joint }
            | Self::DriverError { joint }
            | Self::Stall { joint }
            | Self::ExternalTorque { joint, .. }
            | Self::Collision { joint } => Some(joint),
            _ => None,
        }
    }

    /// Its numeric value with the parameter's name (`temp_c`, `voltage_v`, `torque_nm`), for
    /// the faults that carry one.
    pub fn value(&self) -> Option<(&'static str, f64)> {
        match *self {
            Self::MotorOverTemp { temp_c, .. } | Self::DriverOverTemp { temp_c, .. } => {
                Some(("temp_c", temp_c))
            }
            Self::UnderVoltage { voltage_v } => Some(("voltage_v", voltage_v)),
            Self::ExternalTorque { torque_nm, .. } => Some(("torque_nm", torque_nm)),
            _ => None,
        }
    }

    /// Whether the emulator can apply this fault: the joint exists and the value is finite and
    /// within its parameter's [`FaultParam::range`]. The emulator's `inject` calls it, so no
    /// caller (scenario, web view, Python) can bypass it; scenario validation also calls
    /// [`FaultParam::check`] itself, to point at the line of a bad value.
    pub fn check(&self) -> Result<(), FaultError> {
        if let Some(joint) = self.joint() {
            if !(1..=6).contains(&joint) {
                return Err(FaultError::NoSuchJoint { joint });
            }
        }
        if let Some((name, value)) = self.value() {
            if let Some(param) = self.kind().param(name) {
                param.check(value)?;
            }
        }
        Ok(())
    }

    /// Whether `other` is the same fault in the same place (values such as a temperature
    /// aside): clearing one clears the other.
    pub fn same_site(&self, other: &PiperFault) -> bool {
        let board = |f: &PiperFault| match *f {
            Self::NtcOverTemp { board } => Some(board),
            _ => None,
        };
        self.kind() == other.kind() && self.joint() == other.joint() && board(self) == board(other)
    }
}

/// `name joint N value unit`, e.g. `motor_over_temp joint 2 90 C`, for logs and reports.
impl std::fmt::Display for PiperFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.kind().name())?;
        if let Some(joint) = self.joint() {
            write!(f, " joint {joint}")?;
        }
        match *self {
            Self::MotorOverTemp { temp_c, .. } | Self::DriverOverTemp { temp_c, .. } => {
                write!(f, " {} C", Shown(temp_c))
            }
            Self::UnderVoltage { voltage_v } => write!(f, " {} V", Shown(voltage_v)),
            Self::ExternalTorque { torque_nm, .. } => write!(f, " {} Nm", Shown(torque_nm)),
            Self::NtcOverTemp { board } => write!(f, " {}", board.name()),
            _ => Ok(()),
        }
    }
}

/// A number as `{}` prints it while that is short (24 characters), else in scientific
/// notation: `f64`'s `Display` writes 1e308 as 309 digits, which a message must not echo.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Shown(pub(crate) f64);

impl std::fmt::Display for Shown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plain = self.0.to_string();
        if plain.len() <= 24 {
            f.write_str(&plain)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// A fault named a joint outside 1–6, a non-finite value or a value outside its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultError {
    /// Joint number outside 1–6.
    #[error("joint {joint} does not exist (Piper joints are 1–6)")]
    NoSuchJoint {
        /// The joint given.
        joint: u8,
    },
    /// A temperature, voltage or torque that is NaN or infinite.
    #[error("`{param}` must be a finite number, got {}", Shown(*.value))]
    NotFinite {
        /// The parameter's name (`temp_c`, `voltage_v`, `torque_nm`).
        param: &'static str,
        /// The value given.
        value: f64,
    },
    /// A value outside its parameter's [`FaultParam::range`].
    #[error("`{param}` must be between {} and {}, got {}", Shown(*.min), Shown(*.max), Shown(*.value))]
    OutOfRange {
        /// The parameter's name (`temp_c`, `voltage_v`, `torque_nm`).
        param: &'static str,
        /// The value given.
        value: f64,
        /// Smallest value accepted.
        min: f64,
        /// Largest value accepted.
        max: f64,
    },
}

/// Driver status bits of 0x261–0x266 byte 5 (spec §4.6).
pub mod driver_bits {
    /// Supply under-voltage.
    pub const UNDER_VOLTAGE: u8 = 1 << 0;
    /// Motor over-temperature.
    pub const MOTOR_OVER_TEMP: u8 = 1 << 1;
    /// Driver over-current.
    pub const OVER_CURRENT: u8 = 1 << 2;
    /// Driver over-temperature.
    pub const DRIVER_OVER_TEMP: u8 = 1 << 3;
    /// Collision protection triggered.
    pub const COLLISION: u8 = 1 << 4;
    /// Driver error.
    pub const DRIVER_ERROR: u8 = 1 << 5;
    /// Driver enabled.
    pub const ENABLED: u8 = 1 << 6;
    /// Stall protection triggered.
    pub const STALL: u8 = 1 << 7;
}

/// Gripper status bits of 0x2A8 byte 6 (spec §4.4).
pub mod gripper_bits {
    /// Supply under-voltage.
    pub const UNDER_VOLTAGE: u8 = 1 << 0;
    /// Sensor fault.
    pub const SENSOR_FAULT: u8 = 1 << 4;
    /// Driver enabled.
    pub const ENABLED: u8 = 1 << 6;
    /// Has been zeroed.
    pub const HOMED: u8 = 1 << 7;
}

#[cfg(test)]
mod tests;
