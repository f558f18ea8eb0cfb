//! Interoperability with other CAN tools: a DBC description of the Piper protocol and
//! decoders that print every frame of a capture with units (the Piper's, RobStride's and
//! Damiao's).
//!
//! The Piper's DBC and decoder draw on one signal table ([`piper_messages`]) whose layout a
//! test checks against the driver's own codec (`driver::piper::codec`): the DBC cannot drift
//! from what the driver decodes. Piper and RobStride values come from the driver's codecs; the
//! tables only name them, give their place in the payload and their unit. The Damiao decoder
//! ([`decode_damiao`]) is written from the protocol note instead, apart from both Damiao
//! codecs, and checked against the shared vectors.

mod damiao;
mod decode;
mod piper;
mod robstride_commands;
mod units;

pub use damiao::{decode_damiao, DamiaoWireMotor};
pub use decode::{decode_piper, decode_robstride, decode_robstride_mit, DecodedFrame, Field};
pub use piper::{piper_dbc, piper_messages, probe_field, MessageSpec, SignalSpec};
pub use robstride_commands::decode_robstride_command;
pub use units::{unit_of, UnitSpec};
