//! Realman arm-controller emulator (RM65-B and kin; JSON over TCP, realtime push over UDP;
//! protocol in docs/protocols/realman.md).
//!
//! - [`firmware`]: the synchronous controller state machine on an [`plant::ArmPlant`]
//!   (1 kHz), answering requests and producing arrival events.
//! - [`server`]: the transport — TCP listener in real time or in-memory duplex streams in
//!   virtual time, request framing ([`framing`]), per-client reply streams, the UDP push
//!   ([`push`]) and transport faults ([`faults`]).
//!
//! # Harness API
//!
//! ```no_run
//! # async fn demo() -> Result<(), Box<dyn std::error::Error>> {
//! use sim::realman::model::ArmModel;
//! use sim::realman::{ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanFault, Transport};
//! use tokio::io::AsyncWriteExt;
//!
//! // Virtual time (paused clock): in-memory streams, datagrams on a channel.
//! let emu = RealmanEmulator::spawn(
//!     EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b())),
//!     Transport::InMemory,
//! )
//! .await?;
//! let mut stream = emu.connect("192.168.1.10".parse()?)?;
//! stream.write_all(b"{\"command\":\"get_joint_degree\"}\r\n").await?;
//! let mut datagrams = emu.take_datagrams().expect("in-memory push");
//! emu.inject(RealmanFault::Collision)?;
//! println!("{:?} {:?}", emu.snapshot().joints_rad, datagrams.recv().await);
//! emu.shutdown().await;
//! # Ok(()) }
//! ```
//!
//! `Transport::Tcp(addr)` serves the same controller on a real TCP listener (and pushes over
//! UDP) for external clients such as the vendor SDK (`armhil sim realman`).
//!
//! The motion core is independent of the wire protocol:
//!
//! - [`model`]: the arm models (MDH table, flange, joint ranges, speeds, masses).
//! - [`kinematics`]: flange forward kinematics ([`kinematics::forward`]) and numerical
//!   inverse kinematics ([`kinematics::inverse`]), poses as x, y, z + intrinsic Z-Y-X Euler.
//! - [`planner`]: `movej` / `movel` / `movec` / `moves` trajectories and blending of
//!   connected segments.
//! - [`plant`]: the physical arm, `urdf/rm65b.urdf` in the rapier world at 1 kHz with
//!   torque-driven joint controllers, brakes, currents, temperatures and bus voltage.
//!
//! ```
//! use sim::realman::{kinematics, model::ArmModel, planner};
//!
//! let arm = ArmModel::rm65b();
//! let home = vec![0.0; 6];
//! let target: Vec<f64> = [10.0_f64, 20.0, 30.0, 40.0, 50.0, 60.0].iter().map(|d| d.to_radians()).collect();
//! let pose = kinematics::forward(&arm, &target);
//! let back = kinematics::inverse(&arm, &pose, &target)?;
//! assert!((back[2] - target[2]).abs() < 1e-6);
//! let movej = planner::plan_joint(&arm, &home, &target, 50.0)?;
//! assert_eq!(movej.kind(), planner::MotionKind::Joint);
//! assert!((movej.sample(movej.duration_s())[0] - target[0]).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod facts;
pub mod faults;
pub mod firmware;
pub mod framing;
pub mod ioports;
pub mod kinematics;
pub mod model;
pub mod params;
mod path;
pub mod planner;
pub mod plant;
pub mod profile;
pub mod push;
pub mod server;
pub mod wire;

pub use faults::{build_fault, FaultError, RealmanFault, RealmanFaultCommand, RealmanFaultKind};
pub use firmware::{Answer, ClientId, Controller, ControllerConfig, ControllerError, Event};
pub use profile::FirmwareProfile;
pub use server::{
    EmulatorConfig, RealmanEmulator, RealmanHandle, RealmanMonitor, ServerError, ServerStats,
    Transport,
};
