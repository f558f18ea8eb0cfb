//! The CAN frame type shared by every bus implementation.
//!
//! Frames are plain `Copy` data: an identifier (11-bit standard or 29-bit extended) and 0–8
//! data bytes. Protocol meaning lives in the codecs of `sim` and `driver`, never here.

use std::fmt;
use std::time::Duration;

/// Largest 11-bit standard identifier.
pub const MAX_STANDARD_ID: u16 = 0x7FF;
/// Largest 29-bit extended identifier.
pub const MAX_EXTENDED_ID: u32 = 0x1FFF_FFFF;
/// Largest classic CAN payload in bytes.
pub const MAX_DATA_LEN: usize = 8;

/// Why a frame could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// The identifier does not fit its format (11 or 29 bits).
    #[error("CAN id {id:#x} does not fit a {} identifier (max {max:#x})", if *.extended { "29-bit extended" } else { "11-bit standard" })]
    IdOutOfRange {
        /// The offending identifier.
        id: u32,
        /// Whether an extended identifier was requested.
        extended: bool,
        /// The largest legal identifier of that format.
        max: u32,
    },
    /// More than eight data bytes were given.
    #[error("CAN payload of {len} bytes exceeds the classic CAN maximum of 8")]
    DataTooLong {
        /// The number of bytes given.
        len: usize,
    },
}

/// A CAN identifier: 11-bit standard (SFF) or 29-bit extended (EFF).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CanId {
    /// 11-bit standard identifier.
    Standard(u16),
    /// 29-bit extended identifier.
    Extended(u32),
}

impl CanId {
    /// A standard identifier, checked to fit 11 bits.
    pub fn standard(id: u16) -> Result<Self, FrameError> {
        if id > MAX_STANDARD_ID {
            return Err(FrameError::IdOutOfRange {
                id: u32::from(id),
                extended: false,
                max: u32::from(MAX_STANDARD_ID),
            });
        }
        Ok(Self::Standard(id))
    }

    /// An extended identifier, checked to fit 29 bits.
    pub fn extended(id: u32) -> Result<Self, FrameError> {
        if id > MAX_EXTENDED_ID {
            return Err(FrameError::IdOutOfRange {
                id,
                extended: true,
                max: MAX_EXTENDED_ID,
            });
        }
        Ok(Self::Extended(id))
    }

    /// The numeric identifier without its format flag.
    pub fn raw(self) -> u32 {
        match self {
            Self::Standard(id) => u32::from(id),
            Self::Extended(id) => id,
        }
    }

    /// True for a 29-bit identifier.
    pub fn is_extended(self) -> bool {
        matches!(self, Self::Extended(_))
    }

    /// Arbitration priority: the frame with the smaller key wins the bus.
    ///
    /// The first 11 bits on the wire are the base identifier of both formats. When they tie, a
    /// standard frame wins because its RTR bit is dominant where the extended frame sends the
    /// recessive SRR and IDE bits; two extended frames then compare their 18-bit extensions.
    pub fn arbitration_key(self) -> u64 {
        match self {
            Self::Standard(id) => u64::from(id) << 19,
            Self::Extended(id) => {
                let base = u64::from(id >> 18);
                let extension = u64::from(id & 0x3_FFFF);
                (base << 19) | (1 << 18) | extension
            }
        }
    }
}

impl fmt::Display for CanId {
    /// candump style: three hex digits for standard, eight for extended.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Standard(id) => write!(f, "{id:03X}"),
            Self::Extended(id) => write!(f, "{id:08X}"),
        }
    }
}

/// A classic CAN data frame: identifier plus up to eight bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: CanId,
    len: u8,
    data: [u8; MAX_DATA_LEN],
}

impl CanFrame {
    /// A frame with the given identifier and payload (at most eight bytes).
    pub fn new(id: CanId, data: &[u8]) -> Result<Self, FrameError> {
        if data.len() > MAX_DATA_LEN {
            return Err(FrameError::DataTooLong { len: data.len() });
        }
        let mut bytes = [0u8; MAX_DATA_LEN];
        bytes[..data.len()].copy_from_slice(data);
        Ok(Self {
            id,
            // Cannot truncate: checked against MAX_DATA_LEN above.
            len: data.len() as u8,
            data: bytes,
        })
    }

    /// A standard-ID frame; errors if the id exceeds 11 bits or the data eight bytes.
    pub fn standard(id: u16, data: &[u8]) -> Result<Self, FrameError> {
        Self::new(CanId::standard(id)?, data)
    }

    /// An extended-ID frame; errors if the id exceeds 29 bits or the data eight bytes.
    pub fn extended(id: u32, data: &[u8]) -> Result<Self, FrameError> {
        Self::new(CanId::extended(id)?, data)
    }

    /// The identifier.
    pub fn id(&self) -> CanId {
        self.id
    }

    /// The numeric identifier without its format flag.
    pub fn raw_id(&self) -> u32 {
        self.id.raw()
    }

    /// True for a 29-bit identifier.
    pub fn is_extended(&self) -> bool {
        self.id.is_extended()
    }

    /// The payload (length = DLC).
    pub fn data(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }

    /// The data length code (0–8).
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// True for a frame with no data bytes.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self}")
    }
}

impl fmt::Display for CanFrame {
    /// candump compact form, e.g. `2A1#0100000000000000`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}#", self.id)?;
        for byte in self.data() {
            write!(f, "{byte:02X}")?;
        }
        Ok(())
    }
}

/// A frame as seen by a receiver, with the time it finished on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReceivedFrame {
    /// The frame.
    pub frame: CanFrame,
    /// On SocketCAN: time since the Unix epoch when the frame was received. On the virtual bus:
    /// the bus's configured epoch plus the virtual time at which the frame's last bit was sent.
    pub timestamp: Duration,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_ids_and_payloads_that_do_not_fit() {
        assert!(CanFrame::standard(0x800, &[]).is_err());
        assert!(CanFrame::extended(0x2000_0000, &[]).is_err());
        assert_eq!(
            CanFrame::standard(0x100, &[0; 9]),
            Err(FrameError::DataTooLong { len: 9 })
        );
    }

    #[test]
    fn standard_beats_extended_with_the_same_base_id() {
        let standard = CanId::Standard(0x123);
        let extended = CanId::Extended(0x123 << 18);
        assert!(standard.arbitration_key() < extended.arbitration_key());
        // A lower base id wins regardless of format.
        assert!(
            CanId::Extended(0x122 << 18 | 0x3FFFF).arbitration_key() < standard.arbitration_key()
        );
    }

    #[test]
    fn displays_in_candump_compact_form() {
        let frame = CanFrame::standard(0x2A1, &[1, 0, 0xAB]).unwrap();
        assert_eq!(frame.to_string(), "2A1#0100AB");
        let frame = CanFrame::extended(0x0200_FD01, &[]).unwrap();
        assert_eq!(frame.to_string(), "0200FD01#");
    }
}
