//! Scenario model, runner and reports.
//!
//! A scenario file is parsed in two layers: [`raw`](self) serde structs that reject unknown
//! keys and wrong types, then validation into a typed [`Scenario`]; every error names the
//! file, line and column ([`ScenarioError`]). The grammar is documented in
//! `scenarios/README.md`.

pub(crate) mod error;
mod load;
pub mod model;
mod onekey;
mod raw;
mod validate;
pub mod vocab;

pub use error::{LoadError, Pos, ScenarioError};
pub use load::{discover, load_scenario, parse_scenario};
pub use model::Scenario;
pub use validate::DEFAULT_FIRMWARE;
mod bench;
pub mod device;
mod emulator;
mod piper;
pub mod report;
pub mod result;
pub mod robstride;
mod robstride_raw;
mod runner;

pub use bench::HOST_NODE;
pub use device::{Device, DeviceError, Observation, Reply};
pub use result::{Outcome, ScenarioResult, StepResult, Verdict};
pub use runner::{run_scenario, run_scenario_with, Clock, RunOptions};
#[cfg(test)]
mod tests;
