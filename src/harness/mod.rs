//! The device-independent harness: the scenario grammar core, the runner, the fault schedule,
//! the trace and the reports. Device kinds live in [`crate::devices`].
//!
//! A scenario file is parsed in two layers: `raw` serde structs that reject unknown keys and
//! wrong types, then validation into a typed [`Scenario`]; every error names the file, line and
//! column ([`ScenarioError`]). The grammar is documented in `scenarios/README.md`.

mod load;
pub mod model;
pub(crate) mod raw;
pub(crate) mod validate;

pub use crate::scenario::{elide_long_tokens, LoadError, Pos, ScenarioError};
pub use load::{
    discover, discover_suite, load_scenario, load_suite_file, parse_scenario, parse_variant,
    SuiteFile, SuiteLoader, MAX_SCENARIO_BYTES,
};
pub use model::Scenario;
pub(crate) mod bench;
pub mod report;
pub mod result;
mod runner;

pub use crate::devices::contract::{Device, DeviceError, Reply, TraceColumn};
pub use crate::wiring::{Interrupt, InterruptTrigger};
pub use bench::HOST_NODE;
pub use result::{Outcome, ScenarioResult, StepResult, Verdict};
pub use runner::{
    run_scenario, run_scenario_with, Clock, Link, Omitted, Recording, RunOptions,
    DEFAULT_RECORDING_LIMIT_BYTES, MAX_DEADLINE, MAX_TIME_SCALE,
};
#[cfg(test)]
pub(crate) mod test_support;
#[cfg(test)]
mod tests;
