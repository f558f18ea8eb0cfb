//! Damiao (DM) joint-motor driver (DM4310, DM4340, DM8009, …; protocol note
//! `docs/protocols/damiao.md`), with its own codec.
//!
//! Commands go to the motor's ESC_ID (MIT and the special commands), to 0x100/0x200/0x300 +
//! ESC_ID (position-velocity, velocity, force-position) and to 0x7FF (registers, refresh);
//! every reply comes on the motor's MST_ID. One [`DamiaoDriver`] per bus runs a single receive
//! task and routes each reply by its identifier to the [`DamiaoMotor`] handle with that MST_ID,
//! which checks the ESC_ID nibble in D0. Every request waits for its documented reply with a
//! timeout and returns the decoded feedback or register value, or a typed [`DamiaoError`].
//!
//! ```no_run
//! # async fn demo(bus: std::sync::Arc<dyn bus::CanBus>) -> Result<(), driver::damiao::DamiaoError> {
//! use driver::damiao::{ControlMode, DamiaoDriver, DriverConfig, Model};
//! let driver = DamiaoDriver::new(bus, DriverConfig::default());
//! let motor = driver.motor(0x01, 0x11, Model::DM4310)?;
//! motor.set_control_mode(ControlMode::Velocity).await?;
//! motor.enable().await?;
//! motor.velocity(2.0).await?;
//! # Ok(()) }
//! ```

pub mod codec;
mod driver;
mod error;
pub mod model;
mod motor;
pub mod register;

pub use codec::{
    ControlMode, Feedback, ForcePosCommand, MitCommand, MotorState, RegisterReply, Reply,
    VelocityLen,
};
pub use driver::{DamiaoDriver, DriverConfig, MAX_ESC_ID, MAX_MST_ID};
pub use error::{DamiaoError, MotorError};
pub use model::{Model, RangeTable, Ranges};
pub use motor::DamiaoMotor;
pub use register::{Register, RegisterKind, RegisterValue};
