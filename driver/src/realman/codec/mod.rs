//! The Realman wire codec, written from docs/protocols/realman.md: request encoders, reply and
//! event decoders, the UDP push decoder and the TCP stream splitter. No I/O here.

pub mod decode;
pub mod io;
pub mod message;
pub mod push;
pub mod request;
pub mod splitter;
pub mod types;
pub mod units;

pub use message::{decode_message, Message, ReplyTag};
pub use push::{decode_push, ArmState, JointSpeedUnit};
pub use request::{Expect, Request, Tag};
pub use splitter::{Frame, Splitter};

/// Why a request could not be encoded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EncodeError {
    /// A value is NaN, infinite or too large for the wire field.
    #[error("{field} = {value} cannot be encoded")]
    NotEncodable {
        /// Which argument.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// An integer argument outside its documented range.
    #[error("{field} = {value} is outside {min}..={max}")]
    OutOfRange {
        /// Which argument.
        field: &'static str,
        /// The value given.
        value: i64,
        /// Smallest allowed.
        min: i64,
        /// Largest allowed.
        max: i64,
    },
    /// Wrong number of joints (1..=7; DH tables 6..=7).
    #[error("{got} joint values given")]
    JointCount {
        /// How many were given.
        got: usize,
    },
}

/// Why a received message could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// Not JSON.
    #[error("not JSON: {0}")]
    Json(String),
    /// JSON, but not an object.
    #[error("not a JSON object")]
    NotAnObject,
    /// Neither a `command` nor a `state` string tag (or not the expected one).
    #[error("no command/state tag")]
    NoTag,
    /// A field is missing or has the wrong type or length.
    #[error("field {0:?} missing or malformed")]
    Field(&'static str),
}
