//! The one fault builder: a fault's name and [`FaultArgs`] (as a scenario file, the web view's
//! JSON or Python's keyword arguments gave them) to a [`PiperFault`], checked against the table
//! ([`FaultKind::params`]: which arguments a fault takes, their defaults and ranges). Every
//! front end shows its [`FaultArgError`] unchanged, so the three agree on what is accepted and
//! on every message.

use super::{
    FaultKind, FaultParam, NtcBoard, PiperFault, Shown, BOARD, JOINT, TEMP_C, TORQUE_NM, VOLTAGE_V,
};
use crate::fault_args::{self, shown_word as word, FaultArgError, FaultArgValue, FaultArgs};

/// The Piper fault called `name` built from `args` ([`FaultKind::build`]); an unknown name is
/// refused with the list of known ones.
pub fn build_fault(name: &str, args: &FaultArgs) -> Result<PiperFault, FaultArgError> {
    FaultKind::named(name)?.build(args)
}

impl FaultKind {
    /// The kind called `name`, or an error listing the known names.
    pub fn named(name: &str) -> Result<FaultKind, FaultArgError> {
        fault_args::named("Piper", name, &FaultKind::ALL, FaultKind::name)
    }

    /// The fault of this kind with `args`: an argument the kind does not take is refused, a
    /// required one must be given, an omitted optional one takes the table's default, a joint
    /// is a whole number 1–6, a number is finite and within its parameter's range
    /// ([`FaultParam::check`]) and a word one of its parameter's words. The result passes
    /// [`PiperFault::check`].
    pub fn build(self, args: &FaultArgs) -> Result<PiperFault, FaultArgError> {
        Reader {
            kind: self,
            args,
            clearing: false,
        }
        .fault()
    }

    /// The fault of this kind to clear: as [`FaultKind::build`], but clearing removes the
    /// cause at the fault's site (its joint or board) whatever its values, so a temperature,
    /// voltage or torque is neither needed nor checked (the value is the table's default, or
    /// 0 without one).
    pub fn build_to_clear(self, args: &FaultArgs) -> Result<PiperFault, FaultArgError> {
        Reader {
            kind: self,
            args,
            clearing: true,
        }
        .fault()
    }
}

/// Reads one fault's arguments against its row of the table.
struct Reader<'a> {
    kind: FaultKind,
    args: &'a FaultArgs,
    /// Values (not sites) are ignored: see [`FaultKind::build_to_clear`].
    clearing: bool,
}

impl Reader<'_> {
    fn fault(&self) -> Result<PiperFault, FaultArgError> {
        self.refuse_unknown()?;
        Ok(match self.kind {
            FaultKind::CommLoss => PiperFault::CommLoss {
                joint: self.joint()?,
            },
            FaultKind::MotorOverTemp => PiperFault::MotorOverTemp {
                joint: self.joint()?,
                temp_c: self.value(&TEMP_C)?,
            },
            FaultKind::DriverOverTemp => PiperFault::DriverOverTemp {
                joint: self.joint()?,
                temp_c: self.value(&TEMP_C)?,
            },
            FaultKind::OverCurrent => PiperFault::OverCurrent {
                joint: self.joint()?,
            },
            FaultKind::UnderVoltage => PiperFault::UnderVoltage {
                voltage_v: self.value(&VOLTAGE_V)?,
            },
            FaultKind::DriverError => PiperFault::DriverError {
                joint: self.joint()?,
            },
            FaultKind::Stall => PiperFault::Stall {
                joint: self.joint()?,
            },
            FaultKind::ExternalTorque => PiperFault::ExternalTorque {
                joint: self.joint()?,
                torque_nm: self.value(&TORQUE_NM)?,
            },
            FaultKind::Collision => PiperFault::Collision {
                joint: self.joint()?,
            },
            FaultKind::Estop => PiperFault::Estop,
            FaultKind::NtcOverTemp => PiperFault::NtcOverTemp {
                board: self.board()?,
            },
            FaultKind::GripperSensorFault => PiperFault::GripperSensorFault,
            FaultKind::TeachButton => PiperFault::TeachButton,
        })
    }

    /// The first argument the kind does not take, refused (a typo must not pass silently).
    fn refuse_unknown(&self) -> Result<(), FaultArgError> {
        let Some((name, _)) = self.args.iter().find(|(n, _)| self.kind.param(n).is_none()) else {
            return Ok(());
        };
        let names: Vec<&str> = self.kind.params().iter().map(|p| p.name).collect();
        let takes = if names.is_empty() {
            "no arguments".to_owned()
        } else {
            names.join(", ")
        };
        Err(FaultArgError::at(
            name,
            format!(
                "`{}` takes no `{name}` (it takes: {takes})",
                self.kind.name()
            ),
        ))
    }

    /// The number given for `param`, `None` when omitted.
    fn number(&self, param: &FaultParam) -> Result<Option<f64>, FaultArgError> {
        match self.args.get(param.name) {
            None => Ok(None),
            Some(FaultArgValue::Number(v)) => Ok(Some(*v)),
            Some(FaultArgValue::Text(t)) => Err(FaultArgError::at(
                param.name,
                format!("`{}` must be a number, got {}", param.name, word(t)),
            )),
        }
    }

    /// `Err` when a required parameter is omitted.
    fn missing(&self, param: &FaultParam) -> FaultArgError {
        FaultArgError::missing(self.kind.name(), param.name)
    }

    /// The joint: a whole number 1–6 ([`JOINT`]'s range).
    fn joint(&self) -> Result<u8, FaultArgError> {
        let j = self.number(&JOINT)?.ok_or_else(|| self.missing(&JOINT))?;
        let (min, max) = JOINT.range.unwrap_or((1.0, 6.0));
        if (min..=max).contains(&j) && j.fract() == 0.0 {
            Ok(j as u8)
        } else {
            Err(FaultArgError::at(
                JOINT.name,
                format!(
                    "`joint`: joint index {} out of range, expected {}..={}",
                    Shown(j),
                    Shown(min),
                    Shown(max)
                ),
            ))
        }
    }

    /// A value (temperature, voltage, torque): finite, within its range; the table's default
    /// when omitted.
    fn value(&self, param: &FaultParam) -> Result<f64, FaultArgError> {
        if self.clearing {
            return Ok(param.default.unwrap_or(0.0));
        }
        let Some(v) = self.number(param)? else {
            return param.default.ok_or_else(|| self.missing(param));
        };
        if !v.is_finite() {
            return Err(FaultArgError::at(
                param.name,
                format!("`{}` must be a finite number", param.name),
            ));
        }
        param
            .check(v)
            .map_err(|e| FaultArgError::at(param.name, e.to_string()))
    }

    /// The board: one of [`BOARD`]'s words, the first when omitted.
    fn board(&self) -> Result<NtcBoard, FaultArgError> {
        let given = match self.args.get(BOARD.name) {
            None => BOARD.words.first().copied().unwrap_or_default().to_owned(),
            Some(FaultArgValue::Text(t)) => t.clone(),
            Some(number @ FaultArgValue::Number(_)) => number.to_string(),
        };
        BOARD
            .words
            .contains(&given.as_str())
            .then(|| NtcBoard::from_name(&given))
            .flatten()
            .ok_or_else(|| {
                FaultArgError::at(
                    BOARD.name,
                    format!(
                        "`board`: unknown value {}; expected one of: {}",
                        word(&given),
                        BOARD.words.join(", ")
                    ),
                )
            })
    }
}
