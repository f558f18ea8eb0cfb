//! armhil's drivers: each has its own codec written from the protocol specification and runs
//! over any [`bus::CanBus`] (SocketCAN or the virtual bus).
//!
//! - [`piper`]: AgileX Piper arm (CAN, 11-bit IDs).
//! - [`robstride`]: RobStride actuators (CAN: the private 29-bit protocol, and the
//!   11-bit MIT variant through `robstride::MitMotor`).
//! - [`damiao`]: Damiao (DM) joint motors (CAN, 11-bit IDs).
//! - [`realman`]: Realman arm controllers (JSON over TCP, state over UDP).
//! - [`arm`]: the vendor-neutral Arm API over the Realman and Piper drivers.

pub mod arm;
pub mod damiao;
pub mod piper;
pub mod realman;
pub mod robstride;
