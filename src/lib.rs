//! armhil's scenario harness: YAML scenarios, the runner, reports.
//!
//! The CLI (`armhil run`, `armhil check`) is a thin layer over this library.

pub mod harness;
