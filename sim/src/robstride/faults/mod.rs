//! Faults and warnings: the type-21 fault word, the status-frame fault bits, the typed
//! faults the harness injects (spec §9), and the one builder ([`build_fault`],
//! [`Fault::build`]) that makes a [`MotorFault`] from a front end's [`FaultArgs`], which
//! front ends reach through the monitor's [`FaultTarget`](crate::fault_desk::FaultTarget)
//! (`target.rs`).

mod target;

use serde::{Deserialize, Serialize};

use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};
use crate::piper::faults::Shown;
use crate::robstride::firmware::MAX_CAN_ID;
use crate::robstride::model::Model;

/// A fault the harness can inject (and the models can raise on their own).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Fault {
    /// Winding over-temperature: the injection heats the winding past the fault threshold.
    OverTemperature,
    /// Supply below 12 V: the injection drops the supply to 10 V.
    UnderVoltage,
    /// Supply above the model's limit: the injection raises the supply 2 V past it.
    OverVoltage,
    /// Phase over-current on one phase (one-shot event).
    PhaseOverCurrent(Phase),
    /// Encoder not calibrated: the motor sits in calibration state until calibrated.
    EncoderNotCalibrated,
    /// Stall / I²t overload protection (one-shot event).
    StallOverload,
    /// Gate-driver chip fault (one-shot event).
    GateDriver,
    /// The encoder's reading shifted by `counts` of its 16,384 per turn until cleared: the
    /// firmware's loops and reports see the shaft where it is not (no fault bit: the
    /// firmware cannot tell).
    EncoderGlitch {
        /// The shift, in encoder counts (± half a turn at most).
        counts: i16,
    },
}

/// The faults of one actuator with their values (no `motor`: a robot addresses its actuators
/// by joint), as the actuator contract lists them.
pub fn actuator_fault_table() -> Vec<crate::fault_desk::FaultInfo> {
    Fault::ALL
        .iter()
        .map(|f| crate::fault_desk::FaultInfo {
            name: f.name(),
            description: f.description(),
            params: f.value_infos(),
        })
        .collect()
}

/// A motor phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Phase {
    /// Phase A (fault word bit 16).
    A,
    /// Phase B (fault word bit 4).
    B,
    /// Phase C (fault word bit 5).
    C,
}

impl Fault {
    /// Every fault the emulator can inject (a fault with values as its template: values 0).
    pub const ALL: [Fault; 10] = [
        Fault::OverTemperature,
        Fault::UnderVoltage,
        Fault::OverVoltage,
        Fault::PhaseOverCurrent(Phase::A),
        Fault::PhaseOverCurrent(Phase::B),
        Fault::PhaseOverCurrent(Phase::C),
        Fault::EncoderNotCalibrated,
        Fault::StallOverload,
        Fault::GateDriver,
        Fault::EncoderGlitch { counts: 0 },
    ];

    /// The fault's name in scenario files, logs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Fault::OverTemperature => "over_temperature",
            Fault::UnderVoltage => "under_voltage",
            Fault::OverVoltage => "over_voltage",
            Fault::PhaseOverCurrent(Phase::A) => "phase_a_over_current",
            Fault::PhaseOverCurrent(Phase::B) => "phase_b_over_current",
            Fault::PhaseOverCurrent(Phase::C) => "phase_c_over_current",
            Fault::EncoderNotCalibrated => "encoder_not_calibrated",
            Fault::StallOverload => "stall_overload",
            Fault::GateDriver => "gate_driver",
            Fault::EncoderGlitch { .. } => "encoder_glitch",
        }
    }

    /// The fault with this [`name`](Fault::name) (a fault with values: its template).
    pub fn from_name(name: &str) -> Option<Fault> {
        Fault::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The fault called `name`, or an error listing the known names.
    pub fn named(name: &str) -> Result<Fault, FaultArgError> {
        crate::fault_args::named("RobStride", name, &Fault::ALL, Fault::name)
    }

    /// Its own arguments, besides the motor or joint it is on: the values it takes (what a
    /// fault does, and on which phase, is otherwise in its name).
    pub fn values(self) -> &'static [FaultParam] {
        match self {
            Fault::EncoderGlitch { .. } => &[GLITCH_COUNTS],
            _ => &[],
        }
    }

    /// Its arguments on a RobStride bus: [`MOTOR`], then its [`values`](Fault::values).
    pub fn params(self) -> Vec<FaultParam> {
        std::iter::once(MOTOR)
            .chain(self.values().iter().copied())
            .collect()
    }

    /// This fault on the motor `args` name: an argument the fault does not take is refused,
    /// `motor` must be a CAN ID ([`MOTOR`]) and each value within its range. The one builder
    /// behind the scenario files, the web view and the Python emulator, so all three accept
    /// the same and say the same.
    pub fn build(self, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        let names: Vec<&str> = self.params().iter().map(|p| p.name).collect();
        args.only(self.name(), &names)?;
        let motor = MOTOR.read(self, args)?;
        // A CAN ID is within 1..=127: the cast is exact.
        Ok(MotorFault {
            motor: motor as u8,
            fault: self.with_values(args)?,
        })
    }

    /// The same fault to clear on the motor `args` name: its values may be left out (clearing
    /// removes the cause whatever its size).
    pub fn build_to_clear(self, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        let names: Vec<&str> = self.params().iter().map(|p| p.name).collect();
        args.only(self.name(), &names)?;
        Ok(MotorFault {
            motor: MOTOR.read(self, args)? as u8,
            fault: self,
        })
    }

    /// This fault with its values read from `args` (other arguments are the caller's to
    /// check): a front end that addresses motors otherwise (a robot's joints) builds with it.
    pub fn with_values(self, args: &FaultArgs) -> Result<Fault, FaultArgError> {
        Ok(match self {
            // Within ±8192 (GLITCH_COUNTS): the cast is exact.
            Fault::EncoderGlitch { .. } => Fault::EncoderGlitch {
                counts: GLITCH_COUNTS.read(self, args)? as i16,
            },
            other => other,
        })
    }

    /// Its values as arguments (`counts` of a glitch): what [`Fault::with_values`] reads back,
    /// for a caller holding a typed fault that reaches the motor through the actuator contract.
    pub fn value_args(self) -> FaultArgs {
        match self {
            Fault::EncoderGlitch { counts } => {
                FaultArgs::new().with(GLITCH_COUNTS.name, FaultArgValue::Number(f64::from(counts)))
            }
            _ => FaultArgs::new(),
        }
    }

    /// Its values as a front end offers them (form fields, keyword arguments).
    pub fn value_infos(self) -> Vec<crate::fault_desk::ParamInfo> {
        self.values()
            .iter()
            .map(|p| {
                crate::fault_desk::ParamInfo::required(p.name, p.description)
                    .within(p.min as f64, p.max as f64)
                    .suggesting(Some(FaultArgValue::Number(p.suggested as f64)))
            })
            .collect()
    }

    /// Its name with its values, as a front end shows it applied (`encoder_glitch 100 counts`).
    pub fn label(self) -> String {
        match self {
            Fault::EncoderGlitch { counts } => format!("{} {counts} counts", self.name()),
            other => other.name().to_owned(),
        }
    }

    /// Whether `other` is this fault, whatever its values: clearing one clears the other.
    pub fn same_kind(self, other: Fault) -> bool {
        self.name() == other.name()
    }

    /// What it does to the fault word, and what clears it, in one line.
    pub fn description(self) -> String {
        if let Fault::EncoderGlitch { .. } = self {
            return "shifts the encoder reading by `counts` (16,384 per turn) until cleared; no fault bit".into();
        }
        format!(
            "sets fault word bit 0x{:08X}; clear removes the cause, the latch stays until stop + clear",
            self.word_bit()
        )
    }

    /// The injectable faults whose bit is set in a type-21 fault `word`, in table order.
    pub fn set_in(word: u32) -> Vec<Fault> {
        Fault::ALL
            .into_iter()
            .filter(|f| word & f.word_bit() != 0)
            .collect()
    }

    /// The bit of the type-21 fault word (spec §9.1).
    pub fn word_bit(self) -> u32 {
        match self {
            Fault::OverTemperature => 1 << 0,
            Fault::GateDriver => 1 << 1,
            Fault::UnderVoltage => 1 << 2,
            Fault::OverVoltage => 1 << 3,
            Fault::PhaseOverCurrent(Phase::B) => 1 << 4,
            Fault::PhaseOverCurrent(Phase::C) => 1 << 5,
            Fault::EncoderNotCalibrated => 1 << 7,
            Fault::StallOverload => 1 << 14,
            Fault::PhaseOverCurrent(Phase::A) => 1 << 16,
            // The firmware does not know its encoder lies.
            Fault::EncoderGlitch { .. } => 0,
        }
    }
}

/// A fault on one motor, as [`Fault::build`] makes it from a front end's arguments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MotorFault {
    /// The CAN ID of the motor the fault is on.
    pub motor: u8,
    /// The fault.
    pub fault: Fault,
}

/// One argument of a fault: its name (as in scenario files, the web view's JSON and Python's
/// keyword arguments), what it is, and the whole numbers it accepts. Every argument is
/// required: no fault has a default to fall back on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultParam {
    /// The argument's name.
    pub name: &'static str,
    /// What the number is, in the refusal message (`CAN ID`).
    pub what: &'static str,
    /// What it sets, for a form's tooltip or a docstring.
    pub description: &'static str,
    /// Smallest value accepted.
    pub min: i64,
    /// Largest value accepted.
    pub max: i64,
    /// The value a form starts with.
    pub suggested: i64,
}

/// `motor`: the CAN ID of the motor the fault is on, 1..=127 (the IDs a type-7 command may
/// give a motor).
pub const MOTOR: FaultParam = FaultParam {
    name: "motor",
    what: "CAN ID",
    description: "CAN ID of the motor",
    min: 1,
    max: MAX_CAN_ID as i64,
    suggested: 1,
};

/// Encoder counts per turn: the RobStride family's 14-bit absolute encoder.
pub const ENCODER_COUNTS_PER_TURN: i64 = 16_384;

/// `counts`: an encoder glitch's shift, at most half a turn either way.
pub const GLITCH_COUNTS: FaultParam = FaultParam {
    name: "counts",
    what: "encoder counts",
    description: "shift of the encoder reading, counts of 16,384 per turn",
    min: -ENCODER_COUNTS_PER_TURN / 2,
    max: ENCODER_COUNTS_PER_TURN / 2,
    suggested: 100,
};

impl FaultParam {
    /// The value of this argument in `args` for `fault`: given, a whole number, within range.
    fn read(&self, fault: Fault, args: &FaultArgs) -> Result<i64, FaultArgError> {
        let name = self.name;
        let Some(given) = args.get(name) else {
            return Err(FaultArgError::missing(fault.name(), name));
        };
        let value = match given {
            FaultArgValue::Number(v) if v.is_finite() && v.fract() == 0.0 => *v,
            other => {
                return Err(FaultArgError::at(
                    name,
                    format!("`{name}` must be a whole number, got {other}"),
                ))
            }
        };
        if (self.min as f64..=self.max as f64).contains(&value) {
            // Whole and within an i64 range: the cast is exact.
            Ok(value as i64)
        } else {
            Err(FaultArgError::at(
                name,
                format!(
                    "`{name}`: {} {} out of range, expected {}..={}",
                    self.what,
                    Shown(value),
                    self.min,
                    self.max
                ),
            ))
        }
    }
}

/// The fault called `name` on the motor `args` name ([`Fault::build`]); an unknown name is
/// refused with the list of known ones.
pub fn build_fault(name: &str, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
    Fault::named(name)?.build(args)
}

/// Forced winding temperature (`set_temperature`), °C: from −40 °C (the coldest rating of
/// industrial electronics) to 200 °C (past class-H insulation, 180 °C, where a winding is
/// destroyed). Every model's warning and fault thresholds (93–145 °C) lie well inside.
pub const TEMPERATURE_RANGE_C: (f64, f64) = (-40.0, 200.0);

/// Supply voltage (`set_bus_voltage`), V: from 0 (supply gone) to 120 V, twice the highest
/// rated supply of the family (over-voltage trips near 60 V), which leaves every over-voltage
/// test room.
pub const BUS_VOLTAGE_RANGE_V: (f64, f64) = (0.0, 120.0);

/// Largest external torque on a motor's load (`external_torque`), as a multiple of that
/// model's peak torque: a push ten times what the motor can answer still stalls it, trips the
/// overload and drives the load into anything; a bigger one is not a disturbance a test can
/// mean, and far bigger ones (1e308 N·m) overflow the physics into NaN.
pub const EXTERNAL_TORQUE_PEAK_MULTIPLE: f64 = 10.0;

/// A value the harness asked an emulated motor to take that is not finite or out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValueError {
    /// NaN or infinite.
    #[error("`{param}` must be a finite number, got {}", Shown(*.value))]
    NotFinite {
        /// The parameter's name (`temp_c`, `voltage_v`, `torque_nm`).
        param: &'static str,
        /// The value given.
        value: f64,
    },
    /// Outside its bounds.
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

pub(crate) fn within(
    param: &'static str,
    value: f64,
    (min, max): (f64, f64),
) -> Result<f64, ValueError> {
    if !value.is_finite() {
        Err(ValueError::NotFinite { param, value })
    } else if !(min..=max).contains(&value) {
        Err(ValueError::OutOfRange {
            param,
            value,
            min,
            max,
        })
    } else {
        Ok(value)
    }
}

/// A winding temperature `set_temperature` accepts ([`TEMPERATURE_RANGE_C`]).
pub fn check_temperature_c(temp_c: f64) -> Result<f64, ValueError> {
    within("temp_c", temp_c, TEMPERATURE_RANGE_C)
}

/// A supply voltage `set_bus_voltage` accepts ([`BUS_VOLTAGE_RANGE_V`]).
pub fn check_bus_voltage_v(voltage_v: f64) -> Result<f64, ValueError> {
    within("voltage_v", voltage_v, BUS_VOLTAGE_RANGE_V)
}

/// The largest external torque on a `model`'s load, either way, N·m
/// ([`EXTERNAL_TORQUE_PEAK_MULTIPLE`] × its peak torque).
pub fn max_external_torque_nm(model: Model) -> f64 {
    EXTERNAL_TORQUE_PEAK_MULTIPLE * model.spec().peak_torque_nm
}

/// An external torque `external_torque` accepts on a `model`'s load.
pub fn check_external_torque_nm(model: Model, torque_nm: f64) -> Result<f64, ValueError> {
    let max = max_external_torque_nm(model);
    within("torque_nm", torque_nm, (-max, max))
}

/// Fault word bit 0 of the warning word: over-temperature warning.
pub const WARNING_OVER_TEMP: u32 = 1;

/// The six status-frame fault bits (bits 21..16 of a type-2 identifier, as 0..5) for a fault
/// word, per the spec's §9.2 mapping. Over-voltage has no status bit of its own (the vendor
/// sample's mapping to the encoder bit looks like a bug), so it shows only in the type-21 word.
pub fn status_bits(fault_word: u32) -> u8 {
    let mut bits = 0u8;
    if fault_word & Fault::UnderVoltage.word_bit() != 0 {
        bits |= 1 << 0;
    }
    let over_current = Fault::PhaseOverCurrent(Phase::A).word_bit()
        | Fault::PhaseOverCurrent(Phase::B).word_bit()
        | Fault::PhaseOverCurrent(Phase::C).word_bit()
        | Fault::GateDriver.word_bit();
    if fault_word & over_current != 0 {
        bits |= 1 << 1;
    }
    if fault_word & Fault::OverTemperature.word_bit() != 0 {
        bits |= 1 << 2;
    }
    // Bit 3 (magnetic encoder fault) has no injectable cause; bit 19 stays clear.
    if fault_word & Fault::StallOverload.word_bit() != 0 {
        bits |= 1 << 4;
    }
    if fault_word & Fault::EncoderNotCalibrated.word_bit() != 0 {
        bits |= 1 << 5;
    }
    bits
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_fault_has_its_own_name_and_word_bit() {
        for (i, a) in Fault::ALL.iter().enumerate() {
            assert_eq!(Fault::from_name(a.name()), Some(*a));
            for b in &Fault::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
                assert_ne!(a.word_bit(), b.word_bit());
            }
        }
        assert_eq!(Fault::from_name("melted"), None);
    }

    fn motor(value: FaultArgValue) -> FaultArgs {
        FaultArgs::new().with("motor", value)
    }

    #[test]
    fn every_fault_builds_on_a_motor_by_name() {
        for fault in Fault::ALL {
            let mut args = motor(FaultArgValue::Number(127.0));
            for value in fault.values() {
                args.push(value.name, FaultArgValue::Number(0.0));
            }
            assert_eq!(
                build_fault(fault.name(), &args),
                Ok(MotorFault { motor: 127, fault })
            );
        }
    }

    /// A fault with a value: required, whole, within its range, and refused at its name.
    #[test]
    fn an_encoder_glitch_takes_its_counts() {
        let glitch = |counts: FaultArgValue| {
            build_fault(
                "encoder_glitch",
                &motor(FaultArgValue::Number(3.0)).with("counts", counts),
            )
        };
        assert_eq!(
            glitch(FaultArgValue::Number(-300.0)),
            Ok(MotorFault {
                motor: 3,
                fault: Fault::EncoderGlitch { counts: -300 }
            })
        );
        let far = glitch(FaultArgValue::Number(9000.0)).unwrap_err();
        assert_eq!(
            (far.arg.as_deref(), far.message.as_str()),
            (
                Some("counts"),
                "`counts`: encoder counts 9000 out of range, expected -8192..=8192"
            )
        );
        let missing = build_fault("encoder_glitch", &motor(FaultArgValue::Number(3.0)));
        assert_eq!(
            missing.unwrap_err().message,
            "`encoder_glitch` needs `counts`"
        );
        // Clearing names the motor; the size of the glitch does not matter.
        assert_eq!(
            Fault::EncoderGlitch { counts: 0 }.build_to_clear(&motor(FaultArgValue::Number(3.0))),
            Ok(MotorFault {
                motor: 3,
                fault: Fault::EncoderGlitch { counts: 0 }
            })
        );
    }

    #[test]
    fn the_builder_refuses_with_the_argument_it_is_about() {
        let refused = |name: &str, args: FaultArgs| build_fault(name, &args).unwrap_err();
        let unknown = refused("melted", motor(FaultArgValue::Number(1.0)));
        assert_eq!(unknown.arg, None);
        assert!(
            unknown
                .message
                .starts_with("no RobStride fault `melted`; known: over_temperature, "),
            "{}",
            unknown.message
        );
        let missing = refused("gate_driver", FaultArgs::new());
        assert_eq!(
            (missing.arg, missing.message.as_str()),
            (None, "`gate_driver` needs `motor`")
        );
        for (bad, message) in [
            (0.0, "`motor`: CAN ID 0 out of range, expected 1..=127"),
            (128.0, "`motor`: CAN ID 128 out of range, expected 1..=127"),
            (
                1e308,
                "`motor`: CAN ID 1e308 out of range, expected 1..=127",
            ),
            (2.5, "`motor` must be a whole number, got 2.5"),
            (f64::NAN, "`motor` must be a whole number, got NaN"),
        ] {
            let err = refused("over_voltage", motor(FaultArgValue::Number(bad)));
            assert_eq!(
                (err.arg.as_deref(), err.message.as_str()),
                (Some("motor"), message)
            );
        }
        let word = refused("over_voltage", motor(FaultArgValue::Text("one".into())));
        assert_eq!(word.message, "`motor` must be a whole number, got `one`");
        let extra = refused(
            "under_voltage",
            motor(FaultArgValue::Number(1.0)).with("voltage_v", FaultArgValue::Number(9.0)),
        );
        assert_eq!(extra.arg.as_deref(), Some("voltage_v"));
        assert!(
            extra.message.contains("it takes: motor"),
            "{}",
            extra.message
        );
    }

    #[test]
    fn absurd_values_are_refused_with_a_short_message() {
        let err = check_external_torque_nm(Model::RS03, 1e308).unwrap_err();
        assert_eq!(
            err.to_string(),
            "`torque_nm` must be between -600 and 600, got 1e308"
        );
        assert!(check_temperature_c(1e308).is_err());
        assert!(check_temperature_c(f64::NAN).is_err());
        assert!(check_bus_voltage_v(-1.0).is_err());
        assert!(check_external_torque_nm(Model::RS00, -140.5).is_err());
    }

    #[test]
    fn every_models_thresholds_and_peak_torque_are_within_the_bounds() {
        for model in Model::ALL {
            let spec = model.spec();
            for t in [spec.over_temp_fault_c + 5.0, spec.over_temp_warning_c] {
                assert_eq!(check_temperature_c(t), Ok(t), "{model:?}");
            }
            let over = spec.over_voltage_v + 2.0;
            assert_eq!(check_bus_voltage_v(over), Ok(over), "{model:?}");
            let peak = spec.peak_torque_nm;
            assert_eq!(
                check_external_torque_nm(model, -3.0 * peak),
                Ok(-3.0 * peak)
            );
        }
    }

    #[test]
    fn status_bits_follow_the_documented_mapping() {
        assert_eq!(status_bits(Fault::OverTemperature.word_bit()), 0x04);
        assert_eq!(status_bits(Fault::UnderVoltage.word_bit()), 0x01);
        assert_eq!(
            status_bits(Fault::PhaseOverCurrent(Phase::A).word_bit()),
            0x02
        );
        assert_eq!(status_bits(Fault::GateDriver.word_bit()), 0x02);
        assert_eq!(status_bits(Fault::StallOverload.word_bit()), 0x10);
        assert_eq!(status_bits(Fault::EncoderNotCalibrated.word_bit()), 0x20);
        assert_eq!(status_bits(Fault::OverVoltage.word_bit()), 0);
    }
}
