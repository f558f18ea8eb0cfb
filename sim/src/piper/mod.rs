//! AgileX Piper firmware emulator (CAN, 11-bit IDs; protocol in `shared/protocols/piper.md`).
//!
//! ```no_run
//! # async fn demo(bus: std::sync::Arc<dyn bus::CanBus>) -> Result<(), Box<dyn std::error::Error>> {
//! use sim::piper::{FirmwareProfile, PiperConfig, PiperEmulator, PiperFault, PiperFaultKind};
//! let emu = PiperEmulator::spawn(bus, PiperConfig {
//!     firmware: FirmwareProfile::V1_8_2,
//!     ..PiperConfig::default()
//! })?;
//! emu.inject(PiperFault::JointCommLoss { joint: 3 })?;
//! emu.clear(PiperFaultKind::JointCommLoss { joint: 3 })?;
//! let state = emu.snapshot();
//! println!("{:?}", state.joint_positions_rad);
//! emu.shutdown().await;
//! # Ok(()) }
//! ```
//!
//! Layout: [`codec`] (the emulator's own wire codec), [`profile`] (firmware differences),
//! [`firmware`] (the synchronous master-controller state machine on the physics world),
//! [`emulator`] (its async tasks and the [`PiperHandle`]), [`faults`] (the fault API).

pub mod codec;
mod config;
pub mod emulator;
pub mod faults;
pub mod firmware;
pub mod flash;
pub mod ids;
pub mod kin;
pub mod kinematics;
pub mod motor;
pub mod pose;
pub mod profile;
mod state;
pub mod trajectory;

pub use config::{PiperConfig, PiperError, BUNDLED_URDF};
pub use emulator::{PiperEmulator, PiperHandle};
pub use faults::{FaultError, PiperFault, PiperFaultKind};
pub use firmware::Firmware;
pub use flash::Flash;
pub use profile::FirmwareProfile;
pub use state::{ArmStatusSnapshot, PiperSimState};
