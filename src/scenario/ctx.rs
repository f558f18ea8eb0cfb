//! What layer 2 knows while it walks a scenario ([`Ctx`]) and the checks every key shares:
//! durations, finite numbers, arrays, word choices, which device a step names. Errors carry
//! file, line and column.

use std::path::Path;
use std::time::Duration;

use super::error::{Pos, ScenarioError};
use super::vocab::ErrorClass;
use super::{pos, S};

/// The longest duration any `*_ms` key takes (wait, timeout, `for_ms`, `at_ms`, ...): one hour.
pub(crate) const MAX_MILLIS: u64 = 3_600_000;

/// The longest scenario `name`, in characters (it names the output folder).
pub(crate) const MAX_NAME_CHARS: usize = 100;

/// A validation result; errors carry file, line and column.
pub(crate) type Res<T> = Result<T, Box<ScenarioError>>;

/// What validation knows while it walks a scenario: the file (for errors and relative paths),
/// the bench's devices and the step ids.
pub(crate) struct Ctx<'a> {
    pub file: &'a Path,
    pub text: &'a str,
    /// The bench's devices: name and kind, in bench order.
    pub(crate) devices: Vec<(String, &'static str)>,
    /// The parts of each device a step can address by name (a group's joints), in bench
    /// order; empty for kinds without named parts.
    pub(crate) parts: Vec<Vec<String>>,
    /// The actuator behind each part, where the parts are actuators (a group's joints).
    pub(crate) part_actuators: Vec<Vec<sim::actuator::ActuatorModel>>,
    /// The bench's bus names, in bench order.
    pub(crate) buses: Vec<String>,
    /// Every step's `id:`, in step order.
    pub(crate) step_ids: Vec<Option<String>>,
    /// The variant being loaded: requested value, then (once checked against the file's
    /// `matrix:`) the parameter's name and value.
    pub(crate) variant: Option<String>,
    pub(crate) matrix: Option<(String, String)>,
}

impl<'a> Ctx<'a> {
    pub fn new(file: &'a Path, text: &'a str) -> Self {
        Self {
            file,
            text,
            devices: Vec::new(),
            parts: Vec::new(),
            part_actuators: Vec::new(),
            buses: Vec::new(),
            step_ids: Vec::new(),
            variant: None,
            matrix: None,
        }
    }

    /// A device step's `timeout_ms`, if given.
    pub(crate) fn timeout(&self, value: &Option<S<i64>>) -> Res<Option<Duration>> {
        value
            .as_ref()
            .map(|t| self.positive_millis(t, "timeout_ms"))
            .transpose()
    }

    /// A device step's `expect_error`, if given.
    pub(crate) fn expect_error(&self, value: &Option<S<String>>) -> Res<Option<ErrorClass>> {
        value
            .as_ref()
            .map(|e| self.choice(e, "expect_error", &ErrorClass::NAMES))
            .transpose()
    }

    /// Refuse the first argument in `present` that `do: command` does not take; `bare` says
    /// what a command without arguments still accepts (`"no arguments besides `motor`"`).
    pub(crate) fn only_arguments(
        &self,
        present: &[(&'static str, Pos)],
        allowed: &[&str],
        command: &str,
        bare: &str,
    ) -> Res<()> {
        match present.iter().find(|(key, _)| !allowed.contains(key)) {
            None => Ok(()),
            Some((key, at)) => {
                let takes = if allowed.is_empty() {
                    bare.to_owned()
                } else {
                    allowed.join(", ")
                };
                Err(self.err(
                    *at,
                    format!("`{key}` does not apply to `do: {command}`; it takes: {takes}"),
                ))
            }
        }
    }

    /// Load the variant `value` of a file with a `matrix:`.
    pub fn for_variant(mut self, value: Option<&str>) -> Self {
        self.variant = value.map(str::to_owned);
        self
    }

    /// The value of matrix parameter `key` (`vendor`) for the variant being loaded.
    pub(crate) fn matrix_value(&self, key: &str) -> Option<&str> {
        self.matrix
            .as_ref()
            .filter(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    pub(crate) fn err(&self, at: Pos, message: impl Into<String>) -> Box<ScenarioError> {
        Box::new(ScenarioError::new(self.file, at, message).with_source(self.text))
    }

    /// A bus name (`bus: can1`): what a SocketCAN interface may be called (1 to 15 letters,
    /// digits, `_`, `-` or `.`), since a bench's bus names are the interfaces it stands for.
    pub(crate) fn bus_name(&self, value: &S<String>) -> Res<String> {
        let name = value.value.trim();
        let fits = (1..=15).contains(&name.len())
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
        if !fits {
            return Err(self.err(
                pos(value),
                format!(
                    "bus name `{}`: 1 to 15 letters, digits, `_`, `-` or `.` (an interface name)",
                    value.value
                ),
            ));
        }
        Ok(name.to_owned())
    }

    /// A duration key in milliseconds: 0 ..= [`MAX_MILLIS`] (one hour; longer is a typo that
    /// would otherwise run for years after passing `armhil check`).
    pub(crate) fn millis(&self, value: &S<i64>, key: &str) -> Res<Duration> {
        let ms = u64::try_from(value.value).map_err(|_| {
            self.err(
                pos(value),
                format!("`{key}` must be >= 0 (milliseconds), got {}", value.value),
            )
        })?;
        if ms > MAX_MILLIS {
            return Err(self.err(
                pos(value),
                format!(
                    "`{key}` must be at most {MAX_MILLIS} (one hour, in milliseconds), got {ms}"
                ),
            ));
        }
        Ok(Duration::from_millis(ms))
    }

    pub(crate) fn positive_millis(&self, value: &S<i64>, key: &str) -> Res<Duration> {
        let duration = self.millis(value, key)?;
        if duration.is_zero() {
            return Err(self.err(
                pos(value),
                format!("`{key}` must be > 0 (milliseconds), got 0"),
            ));
        }
        Ok(duration)
    }

    pub(crate) fn finite(&self, value: &S<f64>, key: &str) -> Res<f64> {
        if value.value.is_finite() {
            Ok(value.value)
        } else {
            Err(self.err(pos(value), format!("`{key}` must be a finite number")))
        }
    }

    pub(crate) fn non_negative(&self, value: &S<f64>, key: &str) -> Res<f64> {
        let v = self.finite(value, key)?;
        if v < 0.0 {
            return Err(self.err(pos(value), format!("`{key}` must be >= 0, got {v}")));
        }
        Ok(v)
    }

    pub(crate) fn required<'v, T>(
        &self,
        value: &'v Option<T>,
        key: &str,
        action: &str,
        at: Pos,
    ) -> Res<&'v T> {
        value
            .as_ref()
            .ok_or_else(|| self.err(at, format!("`{action}` needs `{key}`")))
    }

    pub(crate) fn array<const N: usize>(&self, value: &S<Vec<f64>>, key: &str) -> Res<[f64; N]> {
        if value.value.len() != N {
            return Err(self.err(
                pos(value),
                format!(
                    "`{key}` needs exactly {N} numbers, got {}",
                    value.value.len()
                ),
            ));
        }
        let mut out = [0.0; N];
        for (slot, v) in out.iter_mut().zip(&value.value) {
            if !v.is_finite() {
                return Err(self.err(pos(value), format!("`{key}` must hold finite numbers")));
            }
            *slot = *v;
        }
        Ok(out)
    }

    /// The index of the device a step names (or the only device).
    pub(crate) fn device(&self, value: &Option<S<String>>, at: Pos) -> Res<usize> {
        let names = || {
            self.devices
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        match value {
            Some(name) => self
                .devices
                .iter()
                .position(|(d, _)| *d == name.value)
                .ok_or_else(|| {
                    self.err(
                        pos(name),
                        format!(
                            "unknown device `{}`; the bench has: {}",
                            name.value,
                            names()
                        ),
                    )
                }),
            None if self.devices.len() == 1 => Ok(0),
            None => Err(self.err(
                at,
                format!(
                    "the bench has several devices ({}): say which with `device:`",
                    names()
                ),
            )),
        }
    }

    /// The device a step names, which must be of kind `kind` (the kind the step belongs to).
    pub(crate) fn device_of_kind(
        &self,
        value: &Option<S<String>>,
        at: Pos,
        kind: &str,
        what: &str,
    ) -> Res<usize> {
        let index = self.device(value, at)?;
        let (name, actual) = &self.devices[index];
        if *actual != kind {
            let at = value.as_ref().map_or(at, pos);
            return Err(self.err(
                at,
                format!("{what} is for a {kind} device, but device `{name}` is a {actual}"),
            ));
        }
        Ok(index)
    }

    /// The index of the part `name` of device `device` (a joint of a group), or an error
    /// listing the device's parts.
    pub(crate) fn part(&self, device: usize, name: &S<String>, what: &str) -> Res<usize> {
        let parts = self.parts.get(device).map_or(&[][..], Vec::as_slice);
        parts.iter().position(|p| *p == name.value).ok_or_else(|| {
            let names: Vec<&str> = parts.iter().map(String::as_str).collect();
            self.err(
                pos(name),
                format!(
                    "unknown {what} `{}`; device `{}` has: {}{}",
                    name.value,
                    self.devices.get(device).map_or("", |(n, _)| n.as_str()),
                    names.join(", "),
                    super::error::suggestion(&name.value, &names)
                ),
            )
        })
    }

    /// The actuator behind part `part` of device `device`, when its parts are actuators.
    pub(crate) fn part_actuator(
        &self,
        device: usize,
        part: usize,
    ) -> Option<sim::actuator::ActuatorModel> {
        self.part_actuators.get(device)?.get(part).copied()
    }

    pub(crate) fn choice<T: Copy>(
        &self,
        value: &S<String>,
        key: &str,
        table: &[(T, &str)],
    ) -> Res<T> {
        table
            .iter()
            .find(|(_, name)| *name == value.value)
            .map(|(v, _)| *v)
            .ok_or_else(|| {
                let names: Vec<&str> = table.iter().map(|(_, n)| *n).collect();
                self.err(
                    pos(value),
                    format!(
                        "`{key}`: unknown value `{}`; expected one of: {}",
                        value.value,
                        names.join(", ")
                    ),
                )
            })
    }
}
