//! The vendor-neutral Arm API: one [`ArmInterface`] over the Realman and Piper drivers.
//!
//! - [`create_arm`], [`create_arm_from_map`], [`create_arm_from_config`]: the factory.
//! - [`ArmFactoryParam`]: validated parameters ([`params`]), loaded from JSON by [`config`].
//! - [`ArmInterface`]: the trait every backend implements; [`Method`] names its methods for
//!   capability queries ([`ArmInterface::capabilities`], [`ArmInterface::supports`]).
//! - [`RealmanArm`], [`PiperArm`]: the backends, each also constructible from an already
//!   built driver client (`from_client`) for in-memory transports and virtual buses.
//! - Errors: every method returns [`ArmResult`]; [`ArmError`] carries an [`AbcErrorCode`].
//!
//! Units: joints in degrees, joint speeds in RPM, currents in mA, gripper values 0–1000,
//! force sensor in 0.001 N; a [`Pose`] is the flange pose in metres and Z-Y-X Euler radians.
//!
//! ```no_run
//! # async fn demo() -> Result<(), driver::arm::ArmError> {
//! use driver::arm::{create_arm_from_config, MoveOptions};
//! let arm = create_arm_from_config("examples/realman_arm.json")?;
//! arm.connect().await?;
//! arm.move_joint_position(&[0.0, 20.0, 60.0, 0.0, 90.0, 0.0], MoveOptions::blocking(30)).await?;
//! println!("at {:?} deg", arm.get_joint_degree().await?);
//! # Ok(()) }
//! ```

pub mod config;
mod error;
mod factory;
mod interface;
pub mod kinematics;
pub mod params;
mod piper;
mod realman;
mod realtime;
mod types;

pub use config::{load_config, ConfigError};
pub use error::{AbcErrorCode, ArmError, ArmResult};
pub use factory::{create_arm, create_arm_from_config, create_arm_from_map};
pub use interface::{ArmInterface, Method};
pub use params::{ArmFactoryParam, ParamError, Vendor};
pub use piper::{PiperArm, PiperArmOptions, PIPER_CAPABILITIES};
pub use realman::{RealmanArm, RealmanArmOptions, REALMAN_CAPABILITIES};
pub use realtime::{RealtimeCallback, RealtimeHub, RealtimeSubscription};
pub use types::{
    ArmCurrentStatus, ArmForceSensor, ArmRealtimeState, ErrorFlags, GripperState, IkMode,
    JointState, MoveOptions, PeripheralReadWriteParams, Pose, TrajectoryMode,
};
