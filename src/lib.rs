//! armhil's scenario harness: YAML scenarios, the runner, reports, and the device kinds.
//!
//! Layers, each depending only on those above it: [`scenario`] (the grammar core: spans,
//! errors, one-key mappings, the validation context), [`devices`] (the device kinds and their
//! contract, built on [`wiring`]: clock, links, run options), [`harness`] (loading whole
//! scenarios, the runner, reports).
//!
//! The CLI (`armhil run`, `armhil check`) is a thin layer over this library; [`ui`] is the live
//! web view of `armhil sim ... --ui`; [`robots`] reads robot files for `armhil sim robot`,
//! [`rigs`] rig files for `armhil sim rig`.

pub mod devices;
pub mod harness;
pub mod interop;
pub mod rigs;
pub mod robots;
pub mod scenario;
pub mod ui;
pub mod wiring;
