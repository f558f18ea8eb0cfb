//! Interoperability with other CAN tools: a DBC description of the Piper protocol and
//! decoders that print every frame of a capture with units (the Piper's and RobStride's; the
//! Damiao kind's own decoder, `crate::devices::damiao::decode_damiao`, builds its frames from
//! the same [`DecodedFrame`] and [`Field`]).
//!
//! The Piper's DBC and decoder draw on one signal table ([`piper_messages`]) whose layout a
//! test checks against the driver's own codec (`driver::piper::codec`): the DBC cannot drift
//! from what the driver decodes. Piper and RobStride values come from the driver's codecs; the
//! tables only name them, give their place in the payload and their unit.

mod decode;
mod piper;
mod robstride_commands;
mod units;

pub use decode::{decode_piper, decode_robstride, decode_robstride_mit, DecodedFrame, Field};
pub(crate) use decode::{num, text};
pub use piper::{piper_dbc, piper_messages, probe_field, MessageSpec, SignalSpec};
pub use robstride_commands::decode_robstride_command;
pub use units::{unit_of, UnitSpec};
