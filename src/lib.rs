//! armhil's scenario harness: YAML scenarios, the runner, reports, and the device kinds.
//!
//! The CLI (`armhil run`, `armhil check`) is a thin layer over this library; [`ui`] is the live
//! web view of `armhil sim ... --ui`.

pub mod devices;
pub mod harness;
pub mod interop;
pub mod ui;
