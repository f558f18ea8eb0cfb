//! The CAN frame type shared by every bus implementation.
//!
//! Frames are plain `Copy` data: an identifier (11-bit standard or 29-bit extended) and a
//! payload. A classic CAN frame carries 0–8 bytes; a CAN FD frame 0–8, 12, 16, 20, 24, 32, 48
//! or 64 bytes, with its bit-rate-switch (BRS) and error-state-indicator (ESI) flags.
//! Protocol meaning lives in the codecs of `sim` and `driver`, never here.
//!
//! Size: a frame is 72 bytes, the size of Linux's `struct canfd_frame`, classic frames
//! included (20 bytes before CAN FD). The payload room is inline because `CanFrame` is `Copy`
//! (every crate copies frames and `ReceivedFrame`s freely): a boxed or shared CAN FD payload
//! would not be `Copy`, and an enum is as large as its largest variant. What that costs a
//! classic frame is measured by `benches/classic_path.rs`; when CAN FD came in: about 4 ns
//! more to build and copy one (8.5 → 12.5 ns), and about 9 % more instructions for a frame
//! sent and received through the virtual bus (2 650 → 2 890 per frame under callgrind).

use std::fmt;
use std::hash::{Hash, Hasher};
use std::time::Duration;

/// Largest 11-bit standard identifier.
pub const MAX_STANDARD_ID: u16 = 0x7FF;
/// Largest 29-bit extended identifier.
pub const MAX_EXTENDED_ID: u32 = 0x1FFF_FFFF;
/// Largest classic CAN payload in bytes.
pub const MAX_DATA_LEN: usize = 8;
/// Largest CAN FD payload in bytes.
pub const MAX_FD_DATA_LEN: usize = 64;
/// The payload lengths a CAN FD frame can have, indexed by their data length code (DLC).
pub const FD_DATA_LENS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// `flags` bit: bit-rate switch (as Linux's `CANFD_BRS`).
const FLAG_BRS: u8 = 0x01;
/// `flags` bit: error state indicator (as Linux's `CANFD_ESI`).
const FLAG_ESI: u8 = 0x02;
/// `flags` bit: a CAN FD frame (as Linux's `CANFD_FDF`).
const FLAG_FDF: u8 = 0x04;
/// `flags` bit: a 29-bit identifier (this crate's own, outside the FD flag nibble).
const FLAG_EXTENDED: u8 = 0x80;

/// True when `len` is a payload length a CAN FD frame can have (0–8, 12, 16, 20, 24, 32, 48,
/// 64).
pub fn is_fd_data_len(len: usize) -> bool {
    FD_DATA_LENS.contains(&len)
}

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
    /// More than eight data bytes were given for a classic frame.
    #[error("CAN payload of {len} bytes exceeds the classic CAN maximum of 8")]
    DataTooLong {
        /// The number of bytes given.
        len: usize,
    },
    /// A CAN FD payload whose length no data length code encodes.
    #[error(
        "CAN FD payload of {len} bytes is not a CAN FD length (0-8, 12, 16, 20, 24, 32, 48 or \
         64 bytes)"
    )]
    BadFdLength {
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
    /// (A CAN FD frame sends the dominant RRS bit where a classic frame sends RTR, so the
    /// format does not change the key.)
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

/// The flags of a CAN FD frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FdFlags {
    /// Bit-rate switch: the data phase runs at the bus's data bit rate.
    pub brs: bool,
    /// Error state indicator: the sender was error passive.
    pub esi: bool,
}

impl FdFlags {
    /// The flags as SocketCAN's `canfd_frame.flags` carries them, without `CANFD_FDF`:
    /// `CANFD_BRS` 0x01, `CANFD_ESI` 0x02 (also the flag digit of candump's `##` form).
    pub fn bits(self) -> u8 {
        (u8::from(self.brs) * FLAG_BRS) | (u8::from(self.esi) * FLAG_ESI)
    }

    /// BRS and ESI from SocketCAN flag bits; other bits (such as `CANFD_FDF`) are ignored.
    pub fn from_bits(bits: u8) -> Self {
        Self {
            brs: bits & FLAG_BRS != 0,
            esi: bits & FLAG_ESI != 0,
        }
    }
}

/// A CAN data frame: identifier plus payload, classic (up to eight bytes) or CAN FD (up to 64).
///
/// Equality and hashing look at the identifier, the format, the FD flags and the payload.
#[derive(Clone, Copy)]
pub struct CanFrame {
    /// The identifier's number ([`CanId::raw`]).
    raw_id: u32,
    /// Payload bytes in use.
    len: u8,
    /// [`FLAG_EXTENDED`] for a 29-bit identifier; [`FLAG_FDF`], [`FLAG_BRS`], [`FLAG_ESI`]
    /// for a CAN FD frame.
    flags: u8,
    /// The payload, zero past `len`.
    data: [u8; MAX_FD_DATA_LEN],
}

impl CanFrame {
    /// A classic frame with the given identifier and payload (at most eight bytes).
    pub fn new(id: CanId, data: &[u8]) -> Result<Self, FrameError> {
        if data.len() > MAX_DATA_LEN {
            return Err(FrameError::DataTooLong { len: data.len() });
        }
        Ok(Self::with(id, data, 0))
    }

    /// A classic standard-ID frame; errors if the id exceeds 11 bits or the data eight bytes.
    pub fn standard(id: u16, data: &[u8]) -> Result<Self, FrameError> {
        Self::new(CanId::standard(id)?, data)
    }

    /// A classic extended-ID frame; errors if the id exceeds 29 bits or the data eight bytes.
    pub fn extended(id: u32, data: &[u8]) -> Result<Self, FrameError> {
        Self::new(CanId::extended(id)?, data)
    }

    /// A CAN FD frame. The payload must have one of the lengths a CAN FD frame can carry (see
    /// [`FD_DATA_LENS`]); anything else is [`FrameError::BadFdLength`] (it is not padded).
    pub fn fd(id: CanId, data: &[u8], flags: FdFlags) -> Result<Self, FrameError> {
        if !is_fd_data_len(data.len()) {
            return Err(FrameError::BadFdLength { len: data.len() });
        }
        Ok(Self::with(id, data, FLAG_FDF | flags.bits()))
    }

    /// `data` fits: checked by the callers.
    fn with(id: CanId, data: &[u8], flags: u8) -> Self {
        let mut bytes = [0u8; MAX_FD_DATA_LEN];
        bytes[..data.len()].copy_from_slice(data);
        let format = if id.is_extended() { FLAG_EXTENDED } else { 0 };
        Self {
            raw_id: id.raw(),
            // Cannot truncate: at most 64, checked by the callers.
            len: data.len() as u8,
            flags: flags | format,
            data: bytes,
        }
    }

    /// The identifier.
    pub fn id(&self) -> CanId {
        if self.is_extended() {
            CanId::Extended(self.raw_id)
        } else {
            // Cannot truncate: a standard identifier was a u16.
            CanId::Standard(self.raw_id as u16)
        }
    }

    /// The numeric identifier without its format flag.
    pub fn raw_id(&self) -> u32 {
        self.raw_id
    }

    /// True for a 29-bit identifier.
    pub fn is_extended(&self) -> bool {
        self.flags & FLAG_EXTENDED != 0
    }

    /// The payload (of [`CanFrame::len`] bytes).
    pub fn data(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }

    /// The payload length in bytes: 0–8 for a classic frame, one of [`FD_DATA_LENS`] for a
    /// CAN FD frame. For a classic frame this is its data length code.
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// True for a frame with no data bytes.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The 4-bit data length code sent on the wire: the length up to 8; for CAN FD, 9–15
    /// for 12, 16, 20, 24, 32, 48 and 64 bytes.
    pub fn dlc(&self) -> u8 {
        // Cannot truncate: the index of one of 16 lengths.
        FD_DATA_LENS
            .iter()
            .position(|&len| len == usize::from(self.len))
            .unwrap_or(0) as u8
    }

    /// True for a CAN FD frame (FDF set), false for a classic one.
    pub fn is_fd(&self) -> bool {
        self.flags & FLAG_FDF != 0
    }

    /// True for a CAN FD frame whose data phase switches to the data bit rate.
    pub fn brs(&self) -> bool {
        self.flags & FLAG_BRS != 0
    }

    /// True for a CAN FD frame sent by an error-passive node.
    pub fn esi(&self) -> bool {
        self.flags & FLAG_ESI != 0
    }

    /// The CAN FD flags, or `None` for a classic frame.
    pub fn fd_flags(&self) -> Option<FdFlags> {
        self.is_fd().then(|| FdFlags::from_bits(self.flags))
    }
}

impl PartialEq for CanFrame {
    fn eq(&self, other: &Self) -> bool {
        self.raw_id == other.raw_id && self.flags == other.flags && self.data() == other.data()
    }
}

impl Eq for CanFrame {}

impl Hash for CanFrame {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.raw_id.hash(state);
        self.flags.hash(state);
        self.data().hash(state);
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self}")
    }
}

impl fmt::Display for CanFrame {
    /// candump compact form: `2A1#0100000000000000` for a classic frame, `2A1##1AABB…` for a
    /// CAN FD frame (the digit after `##` is the flags: BRS 1, ESI 2).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}#", self.id())?;
        if let Some(flags) = self.fd_flags() {
            write!(f, "#{:X}", flags.bits())?;
        }
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
        let brs = FdFlags {
            brs: true,
            esi: false,
        };
        let frame = CanFrame::fd(CanId::Standard(0x123), &[0xAA, 0xBB, 0xCC], brs).unwrap();
        assert_eq!(frame.to_string(), "123##1AABBCC");
        let both = FdFlags {
            brs: true,
            esi: true,
        };
        let frame = CanFrame::fd(CanId::Extended(0x1ABC_DEF0), &[], both).unwrap();
        assert_eq!(frame.to_string(), "1ABCDEF0##3");
        let frame = CanFrame::fd(CanId::Standard(0x7), &[0x11], FdFlags::default()).unwrap();
        assert_eq!(frame.to_string(), "007##011");
    }

    #[test]
    fn fd_frames_take_exactly_the_fd_lengths() {
        let id = CanId::Standard(0x100);
        let mut accepted = Vec::new();
        for len in 0..=80 {
            match CanFrame::fd(id, &vec![0x5A; len], FdFlags::default()) {
                Ok(frame) => {
                    assert_eq!(frame.len(), len);
                    assert_eq!(frame.data(), &vec![0x5A; len][..]);
                    assert!(frame.is_fd());
                    accepted.push(len);
                }
                Err(error) => {
                    assert_eq!(error, FrameError::BadFdLength { len });
                    let text = error.to_string();
                    assert!(text.contains(&format!("{len} bytes")), "{text}");
                    assert!(text.contains("0-8, 12, 16, 20, 24, 32, 48 or 64"), "{text}");
                }
            }
        }
        assert_eq!(accepted, FD_DATA_LENS);
    }

    #[test]
    fn dlc_codes_follow_the_fd_table() {
        let id = CanId::Standard(0x1);
        for (code, &len) in FD_DATA_LENS.iter().enumerate() {
            let frame = CanFrame::fd(id, &vec![1; len], FdFlags::default()).unwrap();
            assert_eq!(usize::from(frame.dlc()), code, "{len} bytes");
        }
        assert_eq!(CanFrame::standard(1, &[0; 5]).unwrap().dlc(), 5);
    }

    #[test]
    fn classic_and_fd_frames_differ_and_keep_their_flags() {
        let id = CanId::Extended(0x0012_3456);
        let classic = CanFrame::new(id, &[1, 2, 3]).unwrap();
        assert!(!classic.is_fd() && !classic.brs() && !classic.esi());
        assert_eq!(classic.fd_flags(), None);
        assert_eq!(classic.id(), id);
        assert_eq!(classic.raw_id(), 0x0012_3456);
        assert!(classic.is_extended());
        let plain = CanFrame::fd(id, &[1, 2, 3], FdFlags::default()).unwrap();
        assert_ne!(
            classic, plain,
            "an FD frame is not the classic frame with its payload"
        );
        let esi = FdFlags {
            brs: false,
            esi: true,
        };
        let flagged = CanFrame::fd(id, &[1, 2, 3], esi).unwrap();
        assert_ne!(plain, flagged);
        assert!(flagged.esi() && !flagged.brs());
        assert_eq!(flagged.fd_flags(), Some(esi));
        assert_eq!(flagged.id(), id);
        let standard = CanFrame::standard(0x7FF, &[]).unwrap();
        assert_eq!(standard.id(), CanId::Standard(0x7FF));
        assert!(!standard.is_extended());
    }

    #[test]
    fn equal_frames_hash_alike() {
        use std::collections::hash_map::DefaultHasher;
        let hash = |frame: &CanFrame| {
            let mut hasher = DefaultHasher::new();
            frame.hash(&mut hasher);
            hasher.finish()
        };
        let a = CanFrame::fd(CanId::Standard(5), &[9; 12], FdFlags::default()).unwrap();
        let b = CanFrame::fd(CanId::Standard(5), &[9; 12], FdFlags::default()).unwrap();
        assert_eq!(a, b);
        assert_eq!(hash(&a), hash(&b));
        let classic = CanFrame::standard(5, &[9; 8]).unwrap();
        let fd8 = CanFrame::fd(CanId::Standard(5), &[9; 8], FdFlags::default()).unwrap();
        assert_ne!(hash(&classic), hash(&fd8));
    }
}
