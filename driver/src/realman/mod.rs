//! Realman arm controller driver: JSON commands over TCP, state pushed over UDP
//! (docs/protocols/realman.md).
//!
//! - [`codec`]: wire encoding and decoding, no I/O.
//! - [`RealmanClient`]: async client over any byte stream (a tokio `TcpStream` in real time, an
//!   in-memory duplex under a paused clock), pairing each reply with its request by tag.
//! - [`StateFeed`]: the UDP state stream decoded to [`ArmState`] on a watch and a broadcast.

mod client;
pub mod codec;
mod error;

pub use client::{ClientConfig, Handshake, RealmanClient, StateFeed};
pub use codec::decode::{
    AllState, ArmSnapshot, ControllerState, CurrentTrajectory, GripperMode, GripperState,
    JointFlags, PushConfig, SoftwareInfo, ToolFrame, WorkFrame,
};
pub use codec::push::{ArmState, JointSpeedUnit};
pub use codec::request::{CartesianTarget, DhRow, MoveOpts, PushCustom, PushSettings};
pub use codec::types::{
    ArmStatus, Arrival, Axis, Connect, ControllerError, Device, Direction, JointErrorFlags, Pose,
    QuatPose, Smoothing, TrajectoryKind,
};
pub use error::RealmanError;
