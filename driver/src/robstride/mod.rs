//! RobStride actuator driver for the private 29-bit CAN protocol and its MIT variant
//! (11-bit, [`MitMotor`]) (protocol note `docs/protocols/robstride.md`), with its own codecs.
//!
//! One [`RobstrideDriver`] per bus runs a single receive task and routes each frame to the
//! [`Motor`] handle of the motor that sent it. Every request waits for its documented reply
//! with a timeout and returns a typed [`RobstrideError`].
//!
//! ```no_run
//! # async fn demo(bus: std::sync::Arc<dyn bus::CanBus>) -> Result<(), driver::robstride::RobstrideError> {
//! use driver::robstride::{DriverConfig, Model, RobstrideDriver, RunMode};
//! let driver = RobstrideDriver::new(bus, DriverConfig::default());
//! let motor = driver.motor(1, Model::RS03)?;
//! motor.switch_mode(RunMode::Velocity).await?;
//! motor.set_velocity(5.0, 10.0, 20.0).await?;
//! # Ok(()) }
//! ```

pub mod codec;
mod driver;
mod error;
mod mit;
pub mod mit_codec;
pub mod model;
mod motor;
pub mod params;

pub use codec::{FaultReport, Feedback, FeedbackKind, MotorMode, OpControl, StatusFaults};
pub use driver::{DriverConfig, RobstrideDriver, DEFAULT_HOST_ID};
pub use error::RobstrideError;
pub use mit::{MitMode, MitMotor};
pub use mit_codec::{MitIncoming, MitStatus};
pub use model::{Model, RangeTable, Ranges};
pub use motor::{Baud, Motor, Protocol, RunMode};
pub use params::{Param, ParamType, ParamValue};
