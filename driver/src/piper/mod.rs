//! AgileX Piper driver (CAN, 11-bit ids), written from the protocol specification.
//!
//! - The API speaks SI units (rad, rad/s, m, N·m, s) and typed enums; every "keep the
//!   current value" is an `Option`. Status and flag names come from the enums themselves
//!   (`name()`, `Display`, `ALL`, `BITS`).
//! - [`codec`]: pure encoders / decoders for every frame of the protocol, with the wire
//!   integers, sentinels and per-firmware codes (for tools and byte-level tests).
//! - [`PiperBuilder`] → [`Piper`]: one connection per bus, a receive task that keeps a
//!   timestamped [`PiperState`], commands, enable with confirmation, queries with timeouts.
//! - [`kinematics`]: forward kinematics from the SDK's DH tables.
//! - [`limits`]: client-side joint / gripper limits.
//!
//! Everything runs on tokio time, so the driver works in virtual time (paused clock) against
//! the emulator on the virtual bus as well as in real time over SocketCAN.
//!
//! ```
//! # #[tokio::main(flavor = "current_thread", start_paused = true)]
//! # async fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use std::sync::Arc;
//! use std::time::Duration;
//! use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
//! use driver::piper::{PiperBuilder, PiperError, Timeouts};
//!
//! let bus = VirtualBus::new(VirtualBusConfig::default());
//! // With the emulator: `sim::piper::PiperEmulator::spawn(Arc::new(bus.attach("piper")), …)`.
//! // Here nobody answers, so do not wait for feedback at connect.
//! let timeouts = Timeouts { first_feedback: None, ..Timeouts::default() };
//! let piper = PiperBuilder::new(Arc::new(bus.attach("host"))).timeouts(timeouts).connect().await?;
//! match piper.query_joint_limits(1).await {
//!     Err(PiperError::Timeout { waited, .. }) => assert_eq!(waited, Duration::from_millis(500)),
//!     other => panic!("a silent bus cannot answer: {other:?}"),
//! }
//! assert!(!piper.is_ok());
//! piper.disconnect().await;
//! # Ok(()) }
//! ```

mod client;
pub mod codec;
mod error;
pub mod kinematics;
pub mod limits;
mod state;
mod types;

pub use client::{
    BusOpener, DhSelection, FirmwareSelection, Piper, PiperBuilder, PiperConfig, Timeouts,
};
// Typed enums and value types of the codec that the API uses as they are: they carry no
// scaled integers and no sentinels.
pub use codec::{
    AckedCommand, ArmStatusCode, CtrlMode, DriverStatus, FirmwareInfo, FirmwareVersion,
    GripperStatus, JointMask, LeaderHome, MitCommand, MotionStatus, MotorSelect, TeachStatus,
    TrackCommand,
};
pub use error::{LimitedAxis, PiperError};
pub use kinematics::{dh_table, forward_kinematics, DhVariant, LinkPose};
pub use limits::{ClientLimits, LimitPolicy};
pub use state::{BusFault, JointAngles, LinkHealth, PiperState, Stamped};
pub use types::{
    ActiveMove, ArmRole, ArmStatus, CirclePoint, DriverState, EndLimits, EndLimitsUpdate,
    EndMotion, EndPayload, EndPose, GripperCommand, GripperState, GripperTeachParams,
    GripperTeachUpdate, IdShift, Install, JointLimits, JointLimitsUpdate, JointSelect, LeaderMode,
    ModeCommand, MotorState, MoveKind, Pose, RoleOffsets, TrajectoryAck,
};
