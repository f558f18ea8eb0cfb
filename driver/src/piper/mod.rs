//! AgileX Piper driver (CAN, 11-bit ids), written from the protocol specification.
//!
//! - [`codec`]: pure encoders / decoders for every frame of the protocol.
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

pub use client::{
    BusOpener, DhSelection, FirmwareSelection, GripperCommand, MoveKind, Piper, PiperBuilder,
    PiperConfig, Reply, Timeouts,
};
pub use codec::{
    AckedCommand, CollisionLevels, EndParams, EndPoseTarget, FirmwareInfo, FirmwareVersion,
    GripperTeachParams, JointLimits, JointMaxAcc, LeaderHome, MitCommand, MitPacking, MotorSelect,
    ParamCommand,
};
pub use error::{LimitedAxis, PiperError};
pub use kinematics::{forward_kinematics, DhVariant, LinkPose};
pub use limits::{ClientLimits, LimitPolicy};
pub use state::{
    is_abnormal, mdeg_to_rad, rad_to_mdeg, BusFault, EndPose, JointAngles, LinkHealth, PiperState,
    Stamped,
};
