//! The Piper on the bench: our driver (always) plus, in-process, the firmware emulator. One
//! file per concern: [`actions`] (what each step sends), [`stream`] (re-sent targets),
//! [`checks`] (evaluating conditions on observations), [`emulator`] (the in-process emulator's
//! wiring).

mod actions;
pub(super) mod checks;
pub(super) mod emulator;
mod stream;

use std::time::Duration;

use async_trait::async_trait;
use driver::piper::Piper;

use super::{observe, trace};
use crate::devices::{Action, Check, Device, DeviceError, DeviceFault, Reply, TraceColumn};
use crate::scenario::Signal;
use crate::wiring::RunOptions;
use sim::piper::PiperFault;
use stream::Streams;

/// Control of an in-process emulator (the seam between the harness and `sim::piper`).
#[async_trait]
pub(crate) trait EmulatorControl: Send + Sync {
    /// Apply a fault.
    fn inject(&self, fault: &PiperFault) -> Result<(), String>;
    /// Clear one fault, or all.
    fn clear(&self, fault: Option<&PiperFault>) -> Result<(), String>;
    /// `Err` with why once the emulator's physical state is not finite (see
    /// [`Device::emulator_health`]).
    fn health(&self) -> Result<(), String>;
    /// Stop the emulator.
    async fn shutdown(&self);
}

/// A Piper: driver plus optional in-process emulator.
pub(crate) struct PiperDevice {
    pub(super) name: String,
    pub(super) driver: Piper,
    emulator: Option<Box<dyn EmulatorControl>>,
    pub(super) options: RunOptions,
    /// Commands re-sent in the background (`every_ms`).
    pub(super) streams: Streams,
}

impl PiperDevice {
    pub fn new(
        name: &str,
        driver: Piper,
        emulator: Option<Box<dyn EmulatorControl>>,
        options: RunOptions,
    ) -> Self {
        Self {
            name: name.to_owned(),
            driver,
            emulator,
            options,
            streams: Streams::default(),
        }
    }
}

#[async_trait]
impl Device for PiperDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        match action {
            Action::Piper(a) => self.act(a, timeout).await,
            other => Err(DeviceError::step_of_another_kind(
                &self.name, "a Piper", other,
            )),
        }
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        let obs = self.observe();
        for check in checks {
            match check {
                Check::Piper(c) => checks::evaluate_one(c, &obs)?,
                other => return Err((other.describe(), format!("`{}` is a Piper", self.name))),
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        trace::columns(signals)
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        trace::row(signals, &self.observe())
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        let fault = piper_fault(fault, &self.name)?;
        match &self.emulator {
            Some(e) => e.inject(fault).map_err(DeviceError::unsupported),
            None => Err(DeviceError::unsupported(
                "emulator faults need the in-process emulator (not available with --iface)",
            )),
        }
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        let fault = fault.map(|f| piper_fault(f, &self.name)).transpose()?;
        match &self.emulator {
            Some(e) => e.clear(fault).map_err(DeviceError::unsupported),
            None => Err(DeviceError::unsupported(
                "emulator faults need the in-process emulator (not available with --iface)",
            )),
        }
    }

    async fn emulator_health(&self, _last: bool) -> Result<(), String> {
        self.emulator.as_ref().map_or(Ok(()), |e| e.health())
    }

    async fn shutdown(&self) {
        self.streams.stop_all();
        self.driver.disconnect().await;
        if let Some(e) = &self.emulator {
            e.shutdown().await;
        }
    }
}

/// The Piper fault inside a device fault (validation routes only Piper faults here).
fn piper_fault<'f>(fault: &'f DeviceFault, name: &str) -> Result<&'f PiperFault, DeviceError> {
    match fault {
        DeviceFault::Piper(f) => Ok(f),
        other => Err(DeviceError::fault_of_another_kind(name, "a Piper", other)),
    }
}

impl PiperDevice {
    /// The driver's current state in scenario units.
    fn observe(&self) -> super::observe::Observation {
        observe::observe(&self.driver.state(), tokio::time::Instant::now())
    }
}
