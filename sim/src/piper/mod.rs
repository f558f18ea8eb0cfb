//! AgileX Piper firmware emulator (CAN, 11-bit IDs; protocol in `docs/protocols/piper.md`).
//!
//! # Harness API (stable)
//!
//! ```no_run
//! # async fn demo(bus: std::sync::Arc<dyn bus::CanBus>) -> Result<(), Box<dyn std::error::Error>> {
//! use sim::physics::ObstacleShape;
//! use sim::piper::{FirmwareProfile, PiperConfig, PiperEmulator, PiperFault};
//! let emu = PiperEmulator::spawn(bus, PiperConfig {
//!     firmware: FirmwareProfile::V1_8_2,
//!     initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.0, 0.0],
//!     ..PiperConfig::default()
//! })?;
//! emu.inject(PiperFault::CommLoss { joint: 3 })?;
//! emu.clear(PiperFault::CommLoss { joint: 3 })?;
//! let wall = emu.add_obstacle(ObstacleShape::Sphere { radius_m: 0.05 }, [0.3, 0.0, 0.2]);
//! let state = emu.snapshot(); // true joints, velocities, torques, currents, status bytes, flash
//! println!("{:?} {:?}", state.joint_positions_rad, state.status);
//! emu.remove_obstacle(wall);
//! emu.shutdown().await;
//! # Ok(()) }
//! ```
//!
//! - [`PiperEmulator::spawn`] boots the firmware on the current tokio runtime (paused clock =
//!   virtual time, multi-thread = real time) with three tasks: receive, 1 kHz core, transmit.
//! - [`Firmware`] is the same machine without tasks: [`Firmware::handle_frame`],
//!   [`Firmware::tick`] (1 ms), [`Firmware::take_output`] — for synchronous tests.
//! - [`PiperConfig`]: firmware profile, power-on joints, optional JSON state file ("flash"),
//!   optional URDF path (default: the bundled `urdf/piper.urdf`, compiled in).
//!
//! # What the firmware does
//!
//! - Feedback: 0x2A1–0x2A8 and 0x251–0x256 at 200 Hz, 0x261–0x266 at 40 Hz (3040 frames/s),
//!   each group back to back, also while disabled; 0x481–0x486 at 40 Hz when switched on.
//!   Feedback IDs move by the 0x470 feedback offset, the motion block by the control offset.
//! - Every joint has a motor controller ([`motor`]) whose torque drives the rapier world;
//!   position, speed, current (τ / k_t) and effort on the wire come from the simulated state
//!   and that torque. MOVE J/P use a synchronised trapezoid (joint max speed × speed %, max
//!   acceleration from flash), MOVE L/C a Cartesian line/arc through firmware-DH IK, MIT the
//!   host's law with the profile's sign/scale quirks ([`profile`]).
//! - Limits, collision levels, gripper range, zero offsets, leader/follower role and offsets
//!   live in [`flash::Flash`] (persisted atomically when a state file is configured).
//! - Malformed frames (wrong DLC, undefined enum values, bad MIT check nibble) are ignored,
//!   as the firmware ignores them; unknown IDs are ignored.
//!
//! Layout: [`codec`] (the emulator's own wire codec), [`profile`] (firmware differences),
//! [`firmware`] (the synchronous master-controller state machine on the physics world: command
//! families, feedback, protections), [`emulator`] (its async tasks and the [`PiperHandle`]),
//! [`faults`] (the fault table and its one builder, [`build_fault`], which scenario files, the
//! web view and Python all go through).

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
pub use emulator::{PiperEmulator, PiperHandle, PiperMonitor};
pub use faults::{build_fault, FaultError, FaultKind, FaultParam, NtcBoard, PiperFault};
pub use firmware::Firmware;
pub use flash::{Flash, LinkageRole};
pub use profile::FirmwareProfile;
pub use state::{ArmStatusSnapshot, PiperSimState};
