//! Interoperability with other CAN tools: a DBC description of the Piper protocol and a
//! decoder that prints every frame of a capture with units.
//!
//! Both draw on one signal table ([`piper_messages`]) whose layout a test checks against the
//! driver's own codec (`driver::piper::codec`): the DBC cannot drift from what the driver
//! decodes. Values always come from the driver's codec; the table only names them, gives
//! their place in the payload and their unit.

mod decode;
mod piper;
mod robstride_commands;
mod units;

pub use decode::{decode_piper, decode_robstride, decode_robstride_mit, DecodedFrame, Field};
pub use piper::{piper_dbc, piper_messages, probe_field, MessageSpec, SignalSpec};
pub use robstride_commands::decode_robstride_command;
pub use units::{unit_of, UnitSpec};
