//! The device on a bench, as the runner drives it: one implementation per device kind (its
//! `device/` folder), built by the kind's [`KindSpec::build`](super::KindSpec::build).

use std::future::Future;
use std::time::Duration;

use async_trait::async_trait;

use crate::devices::{Action, Check, DeviceFault};
use crate::scenario::{ErrorClass, Signal};

/// Why a device action failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct DeviceError {
    /// Class used by `expect_error`.
    pub class: ErrorClass,
    /// The driver's message.
    pub message: String,
}

impl DeviceError {
    /// An error of `class`.
    pub fn new(class: ErrorClass, message: impl Into<String>) -> Self {
        Self {
            class,
            message: message.into(),
        }
    }

    /// The action or fault is not available on this device / in this mode.
    pub fn unsupported(message: impl Into<String>) -> Self {
        Self::new(ErrorClass::InvalidArgument, message)
    }

    /// An action of another kind sent to device `device`, which `is` (`a Damiao bus`): "a
    /// piper step needs a piper device".
    pub fn step_of_another_kind(device: &str, is: &str, action: &Action) -> Self {
        let kind = action.kind_name();
        Self::unsupported(format!(
            "`{device}` is {is}: a {kind} step needs a {kind} device"
        ))
    }

    /// A fault of another kind sent to device `device`, which `is` (`a Damiao bus`).
    pub fn fault_of_another_kind(device: &str, is: &str, fault: &DeviceFault) -> Self {
        Self::unsupported(format!(
            "`{device}` is {is}: `{}` is a {} fault",
            fault.describe(),
            fault.kind_name()
        ))
    }
}

/// A step's action `act` within its `timeout` (none: the driver's own deadlines), or a
/// timeout error "`late` within N ms" (`late` says what did not come: `enable: no reply`).
pub(crate) async fn within<T>(
    timeout: Option<Duration>,
    late: impl FnOnce() -> String,
    act: impl Future<Output = Result<T, DeviceError>>,
) -> Result<T, DeviceError> {
    match timeout {
        Some(limit) => tokio::time::timeout(limit, act).await.unwrap_or_else(|_| {
            Err(DeviceError::new(
                ErrorClass::Timeout,
                format!("{} within {} ms", late(), limit.as_millis()),
            ))
        }),
        None => act.await,
    }
}

/// What a successful action returned: named values in display form (query replies), in a
/// stable order, and mismatches against the values the step expected.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Reply {
    /// `(name, value)` pairs, e.g. `("firmware", "S-V1.8-8")`.
    pub values: Vec<(String, String)>,
    /// `(name, expected, actual)` for every expected reply value that did not match.
    pub mismatches: Vec<(String, String, String)>,
}

/// One trace column a device fills: its name (without the device prefix the harness adds on
/// multi-device benches), its quantum and its plot group.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceColumn {
    /// Column name with its unit (`j1_deg`, `m1_rad_s`).
    pub name: String,
    /// Quantum the value is rounded to (the snapshot stores integer multiples).
    pub quantum: f64,
    /// Plot group (one panel per group).
    pub group: &'static str,
}

/// A device on the bench: its driver (always) and its emulator (in-process runs), on whatever
/// transport the device speaks.
#[async_trait]
pub trait Device: Send + Sync {
    /// The device's name in the scenario.
    fn name(&self) -> &str;

    /// Perform a driver action. `timeout` overrides the driver's default deadline.
    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError>;

    /// Check conditions against the current state as the driver sees it: `Ok` when every one
    /// holds, else `(expected, actual)` of the first that does not.
    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)>;

    /// The trace columns this device fills for the recorded `signals` (in a stable order).
    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn>;

    /// One trace row, matching [`Device::trace_columns`]: `None` where nothing is known yet.
    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>>;

    /// Apply an emulator fault (needs the in-process emulator).
    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError>;

    /// Clear an emulator fault, or every one when `None`.
    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError>;

    /// Whether the in-process emulator is still sound: `Err` with why when it is not (its
    /// physics diverged to NaN, which the wire would carry as zeros, so checks on the driver's
    /// state could pass on garbage). The runner asks after every step and fails the scenario
    /// with this as an emulator error. Devices without an in-process emulator are always `Ok`.
    ///
    /// An emulator that can only be asked through its own task may answer with its state as
    /// of the previous call (waiting for it between steps would let it run ahead of the next
    /// step's frames and shift every recorded run); `last` (the run is over) waits for a
    /// current answer.
    async fn emulator_health(&self, last: bool) -> Result<(), String> {
        let _ = last;
        Ok(())
    }

    /// Stop the driver and the emulator.
    async fn shutdown(&self);
}
