//! Realman arm-controller emulator (RM65-B and kin; JSON over TCP, realtime push over UDP;
//! protocol in docs/protocols/realman.md).
//!
//! - [`controller`]: the synchronous controller state machine on an [`plant::ArmPlant`]
//!   (1 kHz), answering requests and producing arrival events.
//! - [`server`]: the transport — TCP listener in real time or in-memory duplex streams in
//!   virtual time, request framing ([`framing`]), per-client reply streams, the UDP push
//!   ([`push`]) and transport faults ([`faults`]).
//! - [`model`], [`kinematics`], [`planner`], [`plant`]: the arm itself.

pub mod controller;
pub mod facts;
pub mod faults;
pub mod framing;
pub mod kinematics;
pub mod model;
pub mod params;
pub mod planner;
pub mod plant;
pub mod profile;
pub mod push;
pub mod server;
pub mod wire;

pub use controller::{Answer, ClientId, Controller, ControllerConfig, ControllerError, Event};
pub use faults::{FaultError, RealmanFault, RealmanFaultKind};
pub use profile::FirmwareProfile;
pub use server::{
    EmulatorConfig, RealmanEmulator, RealmanHandle, ServerError, ServerStats, Transport,
};
