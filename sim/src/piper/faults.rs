//! Faults the harness can trigger at run time: [`PiperFault`] with its values, [`FaultKind`] the
//! table of kinds. This is the one description of the Piper's faults: [`FaultKind::name`] is a
//! fault's name in scenario files, [`FaultKind::params`] its parameters and
//! [`FaultKind::description`] what it does on the wire and what clears it.

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

/// Boards with an NTC temperature sensor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
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
        match self {
            NtcBoard::Main => "main",
            NtcBoard::BrakeResistor => "brake_resistor",
        }
    }
}

/// The kinds of [`PiperFault`], without their values: one row per fault of the table above.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
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
};

/// Forced temperature of the over-temperature faults, °C (the default is above every
/// threshold).
const TEMP_C: FaultParam = FaultParam {
    name: "temp_c",
    description: "forced temperature, °C",
    required: false,
    default: Some(90.0),
    range: Some(TEMP_RANGE_C),
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
        match self {
            FaultKind::CommLoss => "comm_loss",
            FaultKind::MotorOverTemp => "motor_over_temp",
            FaultKind::DriverOverTemp => "driver_over_temp",
            FaultKind::OverCurrent => "over_current",
            FaultKind::UnderVoltage => "under_voltage",
            FaultKind::DriverError => "driver_error",
            FaultKind::Stall => "stall",
            FaultKind::ExternalTorque => "external_torque",
            FaultKind::Collision => "collision",
            FaultKind::Estop => "estop",
            FaultKind::NtcOverTemp => "ntc_over_temp",
            FaultKind::GripperSensorFault => "gripper_sensor_fault",
            FaultKind::TeachButton => "teach_button",
        }
    }

    /// The kind with this [`name`](FaultKind::name).
    pub fn from_name(name: &str) -> Option<FaultKind> {
        FaultKind::ALL.into_iter().find(|k| k.name() == name)
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
            FaultKind::UnderVoltage => &[FaultParam {
                name: "voltage_v",
                description: "bus voltage, V (nominal 48 V; drivers trip below 20 V)",
                required: false,
                default: Some(18.0),
                range: Some(VOLTAGE_RANGE_V),
            }],
            FaultKind::ExternalTorque => &[
                JOINT,
                FaultParam {
                    name: "torque_nm",
                    description: "torque, N·m (at most 320 N·m either way)",
                    required: true,
                    default: None,
                    range: Some((-MAX_EXTERNAL_TORQUE_NM, MAX_EXTERNAL_TORQUE_NM)),
                },
            ],
            FaultKind::NtcOverTemp => &[FaultParam {
                name: "board",
                description: "`main` (default) or `brake_resistor`",
                required: false,
                default: None,
                range: None,
            }],
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
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_its_own_name_and_a_description() {
        for (i, a) in FaultKind::ALL.iter().enumerate() {
            assert_eq!(FaultKind::from_name(a.name()), Some(*a));
            assert!(!a.description().is_empty());
            for b in &FaultKind::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
            }
        }
        assert_eq!(FaultKind::from_name("comm_los"), None);
    }

    #[test]
    fn display_starts_with_the_kind_name_and_lists_the_values() {
        let f = PiperFault::MotorOverTemp {
            joint: 2,
            temp_c: 90.0,
        };
        assert_eq!(f.to_string(), "motor_over_temp joint 2 90 C");
        let ntc = PiperFault::NtcOverTemp {
            board: NtcBoard::BrakeResistor,
        };
        assert_eq!(ntc.to_string(), "ntc_over_temp brake_resistor");
        assert_eq!(PiperFault::Estop.to_string(), "estop");
        assert_eq!(
            PiperFault::UnderVoltage { voltage_v: 18.5 }.to_string(),
            "under_voltage 18.5 V"
        );
    }

    #[test]
    fn same_site_ignores_values_but_not_joints_or_boards() {
        let hot = PiperFault::DriverOverTemp {
            joint: 3,
            temp_c: 95.0,
        };
        let any = PiperFault::DriverOverTemp {
            joint: 3,
            temp_c: 0.0,
        };
        let other_joint = PiperFault::DriverOverTemp {
            joint: 4,
            temp_c: 95.0,
        };
        assert!(hot.same_site(&any));
        assert!(!hot.same_site(&other_joint));
        assert!(!hot.same_site(&PiperFault::MotorOverTemp {
            joint: 3,
            temp_c: 95.0
        }));
        let main = PiperFault::NtcOverTemp {
            board: NtcBoard::Main,
        };
        let resistor = PiperFault::NtcOverTemp {
            board: NtcBoard::BrakeResistor,
        };
        assert!(!main.same_site(&resistor));
    }

    #[test]
    fn every_numeric_parameter_has_a_range_holding_its_default() {
        for kind in FaultKind::ALL {
            for p in kind.params() {
                if p.name == "board" {
                    assert_eq!(p.range, None);
                    continue;
                }
                let (min, max) = p.range.unwrap_or_else(|| panic!("{}: no range", p.name));
                assert!(
                    min < max && min.is_finite() && max.is_finite(),
                    "{}",
                    p.name
                );
                if let Some(d) = p.default {
                    assert_eq!(p.check(d), Ok(d), "{}: default outside its range", p.name);
                }
            }
        }
    }

    #[test]
    fn absurd_values_are_refused_with_a_short_message() {
        let torque = PiperFault::ExternalTorque {
            joint: 1,
            torque_nm: 1e308,
        };
        let err = torque.check().unwrap_err();
        assert!(matches!(
            err,
            FaultError::OutOfRange {
                param: "torque_nm",
                ..
            }
        ));
        let text = err.to_string();
        assert_eq!(text, "`torque_nm` must be between -320 and 320, got 1e308");
        for fault in [
            PiperFault::ExternalTorque {
                joint: 6,
                torque_nm: -320.5,
            },
            PiperFault::MotorOverTemp {
                joint: 2,
                temp_c: 1e308,
            },
            PiperFault::DriverOverTemp {
                joint: 2,
                temp_c: f64::NAN,
            },
            PiperFault::UnderVoltage { voltage_v: -1.0 },
            PiperFault::UnderVoltage {
                voltage_v: f64::INFINITY,
            },
        ] {
            let text = fault.check().unwrap_err().to_string();
            assert!(text.len() < 80, "{text}");
        }
        assert_eq!(
            PiperFault::Stall { joint: 7 }.check(),
            Err(FaultError::NoSuchJoint { joint: 7 })
        );
    }

    #[test]
    fn plausible_values_pass() {
        for fault in [
            PiperFault::ExternalTorque {
                joint: 1,
                torque_nm: -320.0,
            },
            PiperFault::MotorOverTemp {
                joint: 6,
                temp_c: 150.0,
            },
            PiperFault::UnderVoltage { voltage_v: 0.0 },
            PiperFault::Estop,
        ] {
            assert_eq!(fault.check(), Ok(()), "{fault}");
        }
    }

    #[test]
    fn display_does_not_echo_hundreds_of_digits() {
        let f = PiperFault::ExternalTorque {
            joint: 1,
            torque_nm: 1e308,
        };
        assert_eq!(f.to_string(), "external_torque joint 1 1e308 Nm");
    }

    #[test]
    fn only_faults_without_required_parameters_may_be_written_bare() {
        assert!(FaultKind::Estop.bare_ok());
        assert!(FaultKind::UnderVoltage.bare_ok());
        assert!(FaultKind::NtcOverTemp.bare_ok());
        assert!(!FaultKind::CommLoss.bare_ok());
        assert!(!FaultKind::ExternalTorque.bare_ok());
    }
}
