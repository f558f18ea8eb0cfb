//! Realman arm controller driver: JSON commands over TCP, state pushed over UDP
//! (docs/protocols/realman.md).
//!
//! - [`codec`]: wire encoding and decoding, no I/O.
//! - [`RealmanClient`]: async client over any byte stream (a tokio `TcpStream` in real time, an
//!   in-memory duplex under a paused clock), pairing each reply with its request by tag.
//! - [`StateFeed`]: the UDP state stream decoded to [`ArmState`] on a watch and a broadcast.
//!
//! ```no_run
//! # async fn demo() -> Result<(), Box<dyn std::error::Error>> {
//! use driver::realman::{ClientConfig, JointSpeedUnit, MoveOpts, RealmanClient, StateFeed};
//! let arm = RealmanClient::connect("192.168.1.18:8080", ClientConfig::default()).await?;
//! let info = arm.handshake().await?;
//! println!("{} with {} joints", info.software.product_version, info.software.dof);
//! let feed = StateFeed::bind("0.0.0.0:8089", JointSpeedUnit::default()).await?;
//! // Blocking joint move at 20 % speed: returns when the arrival event comes.
//! arm.movej(&[0.0, 0.3, 0.5, 0.0, 0.8, 0.0], MoveOpts::speed(20), true).await?;
//! if let Some(state) = feed.latest() {
//!     println!("joints {:?} rad, errors {:?}", state.joints_rad, state.errors);
//! }
//! # Ok(()) }
//! ```

mod client;
pub mod codec;
mod error;

pub use client::{ClientConfig, Handshake, RealmanClient, StateFeed};
pub use codec::decode::{
    AllState, ArmSnapshot, ControllerState, CurrentTrajectory, GripperMode, GripperState,
    JointFlags, PushConfig, SoftwareInfo, ToolFrame, WorkFrame,
};
pub use codec::io::{IoLevels, IoPortState, PlusBaseInfo, SoftwareVersion, ToolIoState};
pub use codec::push::{ArmState, JointSpeedUnit};
pub use codec::request::{CartesianTarget, DhRow, MoveOpts, PushCustom, PushSettings};
pub use codec::types::{
    ArmStatus, Arrival, Axis, Connect, ControllerError, Device, Direction, JointErrorFlags, Pose,
    QuatPose, Smoothing, TrajectoryKind,
};
pub use error::RealmanError;
