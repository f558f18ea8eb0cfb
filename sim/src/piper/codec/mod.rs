//! The emulator's own Piper codec, written from the spec (never shared with the driver).
//!
//! Every multi-byte field is big-endian. Scaled integers stay in here: [`host`] decodes what
//! the master controller receives, [`arm`] encodes what it sends.

pub mod arm;
pub mod host;
pub mod mit;

use bus::CanFrame;

/// Why a host frame was not accepted. The firmware ignores such frames.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// Piper uses 11-bit identifiers only.
    #[error("extended id {id:#x} is not part of the Piper protocol")]
    Extended {
        /// The identifier.
        id: u32,
    },
    /// Not an identifier the master controller listens to.
    #[error("id {id:#05x} is not a host command")]
    UnknownId {
        /// The identifier.
        id: u16,
    },
    /// The frame has the wrong data length.
    #[error("id {id:#05x}: DLC {dlc}, expected {expected}")]
    WrongDlc {
        /// The identifier (without control offset).
        id: u16,
        /// DLC received.
        dlc: usize,
        /// DLC required.
        expected: usize,
    },
    /// A field holds a value the protocol does not define.
    #[error("id {id:#05x}: invalid {field} value {value:#x}")]
    InvalidValue {
        /// The identifier (without control offset).
        id: u16,
        /// Field name.
        field: &'static str,
        /// Raw value.
        value: u32,
    },
    /// An MIT frame failed its check nibble.
    #[error("id {id:#05x}: MIT check nibble {got:#x}, expected {expected:#x}")]
    BadCheck {
        /// The identifier.
        id: u16,
        /// Nibble computed from bytes 0–6.
        expected: u8,
        /// Nibble received.
        got: u8,
    },
}

pub(crate) fn be_u16(d: &[u8; 8], at: usize) -> u16 {
    u16::from_be_bytes([d[at], d[at + 1]])
}

pub(crate) fn be_i16(d: &[u8; 8], at: usize) -> i16 {
    i16::from_be_bytes([d[at], d[at + 1]])
}

pub(crate) fn be_i32(d: &[u8; 8], at: usize) -> i32 {
    i32::from_be_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]])
}

/// A standard frame. Ids are masked to 11 bits and payloads cut to 8 bytes, so building the
/// frame cannot fail.
pub(crate) fn frame(id: u16, data: &[u8]) -> CanFrame {
    let data = &data[..data.len().min(bus::MAX_DATA_LEN)];
    match CanFrame::new(bus::CanId::Standard(id & bus::MAX_STANDARD_ID), data) {
        Ok(f) => f,
        Err(e) => unreachable!("an 11-bit id with at most 8 bytes is always a valid frame: {e}"),
    }
}
