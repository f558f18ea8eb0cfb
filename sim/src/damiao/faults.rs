//! The errors a Damiao motor reports in its feedback's state nibble (note §5), as faults a
//! test bench injects: their names, the one builder that reads a front end's [`FaultArgs`]
//! for them, and the set of errors a motor has latched.
//!
//! Injecting a fault sets its cause (a supply past a threshold, a hot board or coil, an
//! over-current or overload event) and latches the error at once: the motor stops. `clear`
//! removes the cause; the latch stays until the host's `FB` (clear error), which clears only
//! the errors whose cause is gone. Thresholds trip at the register's value or beyond (OV and
//! OT at or above, UV at or below).

use crate::damiao::model::Model;
use crate::damiao::registers::{rid, RegisterFile};
use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};
use crate::fault_desk::{FaultInfo, ParamInfo};
use crate::piper::faults::Shown;

/// One of the motor's errors (state nibbles 8..=0xE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Fault {
    /// 8: supply at or above OV_Value.
    OverVoltage,
    /// 9: supply at or below UV_Value.
    UnderVoltage,
    /// A: phase over-current (an event; its cause lasts until cleared).
    OverCurrent,
    /// B: driver (MOS) board at or above OT_Value.
    MosOverTemperature,
    /// C: coil (rotor) at or above OT_Value.
    CoilOverTemperature,
    /// D: communication lost (the CAN timeout fired, or injected).
    CommLost,
    /// E: overload (an event; its cause lasts until cleared).
    Overload,
}

/// Highest supply voltage a fault may set (V): past any Damiao rating (48 V) with room.
pub const VOLTAGE_MAX_V: f64 = 120.0;
/// Highest temperature a fault or the side door may set (°C): past class-H insulation.
pub const TEMPERATURE_MAX_C: f64 = 200.0;

/// The thresholds the motor's registers hold now (what an injected value must reach).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// OV_Value (V).
    pub over_voltage_v: f64,
    /// UV_Value (V).
    pub under_voltage_v: f64,
    /// OT_Value (°C).
    pub over_temperature_c: f64,
}

impl Thresholds {
    /// A `model`'s thresholds at power-on (its default OV_Value, UV_Value and OT_Value): the
    /// fault table a front end can offer before a motor runs.
    pub fn power_on(model: Model) -> Self {
        let registers = RegisterFile::defaults(model, 0, 0, 0);
        Self {
            over_voltage_v: registers.number(rid::OV_VALUE),
            under_voltage_v: registers.number(rid::UV_VALUE),
            over_temperature_c: registers.number(rid::OT_VALUE),
        }
    }
}

/// A fault ready to apply: which, and the value its cause takes (a voltage or temperature;
/// `None` for the events).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Injection {
    /// The fault.
    pub fault: Fault,
    /// Supply voltage (V) or temperature (°C) the cause sets, if the fault has one.
    pub value: Option<f64>,
}

/// The value a fault's cause takes, as a front end names it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ValueParam {
    name: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    suggested: f64,
}

impl Fault {
    /// Every fault, in state-nibble order.
    pub const ALL: [Fault; 7] = [
        Fault::OverVoltage,
        Fault::UnderVoltage,
        Fault::OverCurrent,
        Fault::MosOverTemperature,
        Fault::CoilOverTemperature,
        Fault::CommLost,
        Fault::Overload,
    ];

    /// Its name in scenario files, the web view and snapshots.
    pub fn name(self) -> &'static str {
        match self {
            Fault::OverVoltage => "over_voltage",
            Fault::UnderVoltage => "under_voltage",
            Fault::OverCurrent => "over_current",
            Fault::MosOverTemperature => "mos_over_temperature",
            Fault::CoilOverTemperature => "coil_over_temperature",
            Fault::CommLost => "comm_lost",
            Fault::Overload => "overload",
        }
    }

    /// The state nibble the feedback frame carries while it is latched.
    pub fn code(self) -> u8 {
        match self {
            Fault::OverVoltage => 0x8,
            Fault::UnderVoltage => 0x9,
            Fault::OverCurrent => 0xA,
            Fault::MosOverTemperature => 0xB,
            Fault::CoilOverTemperature => 0xC,
            Fault::CommLost => 0xD,
            Fault::Overload => 0xE,
        }
    }

    /// The fault a state nibble reports, if it is an error.
    pub fn from_code(code: u8) -> Option<Fault> {
        Fault::ALL.into_iter().find(|f| f.code() == code)
    }

    /// The fault called `name`, or an error listing the known names.
    pub fn named(name: &str) -> Result<Fault, FaultArgError> {
        crate::fault_args::named("Damiao", name, &Fault::ALL, Fault::name)
    }

    /// Its bit in an [`ErrorSet`].
    fn bit(self) -> u8 {
        1 << (self.code() - 0x8)
    }

    /// What injecting it does, in one line.
    pub fn description(self) -> String {
        let cause = match self {
            Fault::OverVoltage => "raises the supply to `voltage_v` (default OV_Value + 2 V)",
            Fault::UnderVoltage => "drops the supply to `voltage_v` (default UV_Value − 2 V)",
            Fault::OverCurrent => "a phase over-current event",
            Fault::MosOverTemperature => {
                "heats the driver board to `temperature_c` (default OT_Value + 5 °C)"
            }
            Fault::CoilOverTemperature => {
                "heats the coil to `temperature_c` (default OT_Value + 5 °C)"
            }
            Fault::CommLost => "latches communication lost, as the CAN timeout would",
            Fault::Overload => "an overload event",
        };
        format!(
            "{cause}; state {:X}, the motor stops; clear removes the cause, the latch stays until FB",
            self.code()
        )
    }

    /// The value its cause takes, if any, with the range that trips it under `limits`.
    fn value_param(self, limits: &Thresholds) -> Option<ValueParam> {
        let volts = |min: f64, max: f64, suggested: f64| ValueParam {
            name: "voltage_v",
            unit: "V",
            min,
            max,
            suggested,
        };
        let heat = || {
            let ot = limits.over_temperature_c;
            ValueParam {
                name: "temperature_c",
                unit: "°C",
                min: ot,
                max: TEMPERATURE_MAX_C.max(ot),
                suggested: (ot + 5.0).min(TEMPERATURE_MAX_C.max(ot)),
            }
        };
        match self {
            Fault::OverVoltage => {
                let ov = limits.over_voltage_v;
                let max = VOLTAGE_MAX_V.max(ov + 2.0);
                Some(volts(ov, max, ov + 2.0))
            }
            Fault::UnderVoltage => {
                let uv = limits.under_voltage_v.max(0.0);
                Some(volts(0.0, uv, (uv - 2.0).max(0.0)))
            }
            Fault::MosOverTemperature | Fault::CoilOverTemperature => Some(heat()),
            Fault::OverCurrent | Fault::CommLost | Fault::Overload => None,
        }
    }

    /// Its entry in a fault table, with the value's range under `limits`.
    pub fn info(self, limits: &Thresholds) -> FaultInfo {
        let params = self
            .value_param(limits)
            .map(|p| {
                let mut info = ParamInfo::required(
                    p.name,
                    format!(
                        "the value its cause takes ({}; omitted: the default)",
                        p.unit
                    ),
                )
                .within(p.min, p.max)
                .suggesting(Some(FaultArgValue::Number(p.suggested)));
                info.required = false;
                info
            })
            .into_iter()
            .collect();
        FaultInfo {
            name: self.name(),
            description: self.description(),
            params,
        }
    }

    /// This fault with its value read from `args` (optional; its default when omitted),
    /// refused when it would not trip under `limits` or `args` holds anything else.
    pub fn build(self, args: &FaultArgs, limits: &Thresholds) -> Result<Injection, FaultArgError> {
        let param = self.value_param(limits);
        let known: Vec<&str> = param.iter().map(|p| p.name).collect();
        args.only(self.name(), &known)?;
        let Some(param) = param else {
            return Ok(Injection {
                fault: self,
                value: None,
            });
        };
        let value = match args.get(param.name) {
            None => param.suggested,
            Some(FaultArgValue::Number(x)) if x.is_finite() => *x,
            Some(other) => {
                return Err(FaultArgError::at(
                    param.name,
                    format!("`{}` must be a finite number, got {other}", param.name),
                ))
            }
        };
        if !(param.min..=param.max).contains(&value) {
            return Err(FaultArgError::at(
                param.name,
                format!(
                    "`{}`: {} {} does not trip {}; expected {}..={}",
                    param.name,
                    Shown(value),
                    param.unit,
                    self.name(),
                    Shown(param.min),
                    Shown(param.max)
                ),
            ));
        }
        Ok(Injection {
            fault: self,
            value: Some(value),
        })
    }

    /// This fault to clear: a value may be given (ignored) but nothing else.
    pub fn build_to_clear(
        self,
        args: &FaultArgs,
        limits: &Thresholds,
    ) -> Result<Fault, FaultArgError> {
        let known: Vec<&str> = self.value_param(limits).iter().map(|p| p.name).collect();
        args.only(self.name(), &known)?;
        Ok(self)
    }
}

/// The whole table under `limits`, in state-nibble order.
pub fn table(limits: &Thresholds) -> Vec<FaultInfo> {
    Fault::ALL.iter().map(|f| f.info(limits)).collect()
}

/// The errors a motor has latched.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ErrorSet(u8);

impl ErrorSet {
    /// Latch `fault`.
    pub fn insert(&mut self, fault: Fault) {
        self.0 |= fault.bit();
    }

    /// Unlatch `fault`.
    pub fn remove(&mut self, fault: Fault) {
        self.0 &= !fault.bit();
    }

    /// Whether `fault` is latched.
    pub fn contains(self, fault: Fault) -> bool {
        self.0 & fault.bit() != 0
    }

    /// Whether nothing is latched.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The latched faults, in state-nibble order.
    pub fn iter(self) -> impl Iterator<Item = Fault> {
        Fault::ALL.into_iter().filter(move |f| self.contains(*f))
    }

    /// The nibble the feedback shows: the lowest latched code (the note has one nibble for
    /// several errors; the emulator shows the lowest, so over-voltage outranks the rest), or
    /// `None` with nothing latched.
    pub fn state_nibble(self) -> Option<u8> {
        self.iter().next().map(Fault::code)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: Thresholds = Thresholds {
        over_voltage_v: 32.4,
        under_voltage_v: 12.0,
        over_temperature_c: 120.0,
    };

    #[test]
    fn names_and_codes_are_distinct_and_round_trip() {
        for (i, a) in Fault::ALL.iter().enumerate() {
            assert_eq!(Fault::named(a.name()), Ok(*a));
            assert_eq!(Fault::from_code(a.code()), Some(*a));
            for b in &Fault::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
                assert_ne!(a.code(), b.code());
            }
        }
        assert_eq!(Fault::from_code(1), None);
        let unknown = Fault::named("melted").unwrap_err();
        assert!(
            unknown.message.contains("over_voltage, under_voltage"),
            "{}",
            unknown.message
        );
    }

    #[test]
    fn a_value_is_optional_checked_and_only_where_the_fault_has_one() {
        let none = Fault::OverVoltage
            .build(&FaultArgs::new(), &LIMITS)
            .unwrap();
        assert_eq!(none.value, Some(34.4));
        let args = |x: f64| FaultArgs::new().with("voltage_v", FaultArgValue::Number(x));
        assert_eq!(
            Fault::UnderVoltage
                .build(&args(5.0), &LIMITS)
                .unwrap()
                .value,
            Some(5.0)
        );
        let refused = Fault::UnderVoltage.build(&args(20.0), &LIMITS).unwrap_err();
        assert_eq!(refused.arg.as_deref(), Some("voltage_v"));
        assert!(
            refused.message.contains("does not trip under_voltage"),
            "{}",
            refused.message
        );
        let extra = Fault::Overload.build(&args(5.0), &LIMITS).unwrap_err();
        assert!(
            extra.message.contains("takes no arguments"),
            "{}",
            extra.message
        );
        let word = FaultArgs::new().with("temperature_c", FaultArgValue::Text("hot".into()));
        assert!(Fault::CoilOverTemperature.build(&word, &LIMITS).is_err());
        assert_eq!(
            Fault::CommLost
                .build(&FaultArgs::new(), &LIMITS)
                .unwrap()
                .value,
            None
        );
    }

    #[test]
    fn power_on_thresholds_follow_the_supply() {
        let low = Thresholds::power_on(Model::DM4310);
        let high = Thresholds::power_on(Model::DM4310_48V);
        assert!(low.under_voltage_v < 24.0 && low.over_voltage_v > 24.0);
        assert!(high.under_voltage_v < 48.0 && high.over_voltage_v > 48.0);
        assert!(high.over_voltage_v > low.over_voltage_v);
    }

    #[test]
    fn the_table_offers_the_tripping_range() {
        let table = table(&LIMITS);
        assert_eq!(table.len(), 7);
        let heat = &table[3].params[0];
        assert_eq!(
            (heat.name, heat.min, heat.max),
            ("temperature_c", Some(120.0), Some(200.0))
        );
        assert!(!heat.required);
        assert!(table[2].params.is_empty());
    }

    #[test]
    fn the_lowest_latched_code_is_shown() {
        let mut set = ErrorSet::default();
        assert_eq!(set.state_nibble(), None);
        set.insert(Fault::Overload);
        set.insert(Fault::CommLost);
        assert_eq!(set.state_nibble(), Some(0xD));
        set.remove(Fault::CommLost);
        assert_eq!(set.state_nibble(), Some(0xE));
        assert_eq!(set.iter().collect::<Vec<_>>(), [Fault::Overload]);
    }
}
