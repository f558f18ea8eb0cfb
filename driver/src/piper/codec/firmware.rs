//! 0x4AF firmware version: the query, the 11-frame (88-byte) reply and its parsing.

use std::fmt;

use bus::CanFrame;

use super::{frame, ids, MitPacking, MoveMode};

/// Bytes in a complete firmware reply (11 frames × 8).
pub const FIRMWARE_REPLY_LEN: usize = 88;

/// Encode the 0x4AF firmware query (`01 00 …`, as the SDK sends it).
pub fn encode_firmware_query() -> CanFrame {
    frame(ids::FIRMWARE, &[1, 0, 0, 0, 0, 0, 0, 0])
}

/// One received 0x4AF reply frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct FirmwarePart {
    /// Payload bytes (only `len` are valid).
    pub data: [u8; 8],
    /// Payload length.
    pub len: u8,
}

impl FirmwarePart {
    /// Decode a 0x4AF frame; `None` for a frame that is a query (another host's, or our own
    /// on a loopback interface), which must not enter the reply buffer.
    pub fn decode(frame: &CanFrame) -> Option<Self> {
        let d = frame.data();
        if d == [1] || d == [1, 0, 0, 0, 0, 0, 0, 0] {
            return None;
        }
        let mut data = [0u8; 8];
        data[..d.len()].copy_from_slice(d);
        Some(Self {
            data,
            len: d.len() as u8,
        })
    }

    /// The valid payload bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.len).min(8)]
    }
}

/// Parsed `S-Vmaj.min-patch` software version.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct FirmwareVersion {
    /// Major.
    pub major: u8,
    /// Minor.
    pub minor: u8,
    /// Patch.
    pub patch: u8,
}

impl FirmwareVersion {
    /// A version from its parts.
    pub const fn new(major: u8, minor: u8, patch: u8) -> Self {
        Self {
            major,
            minor,
            patch,
        }
    }

    /// Parse `S-V1.8-8` (or `1.8-8`, `V1.8-8`); `None` if it does not have that shape.
    pub fn parse(text: &str) -> Option<Self> {
        let text = text.trim_end_matches('\0').trim();
        let text = text.strip_prefix("S-").unwrap_or(text);
        let text = text.strip_prefix('V').unwrap_or(text);
        let (major_minor, patch) = text.split_once('-')?;
        let (major, minor) = major_minor.split_once('.')?;
        Some(Self {
            major: major.parse().ok()?,
            minor: minor.parse().ok()?,
            patch: patch.parse().ok()?,
        })
    }

    /// The MIT frame packing this firmware expects.
    pub fn mit_packing(self) -> MitPacking {
        if self >= Self::new(1, 8, 8) {
            MitPacking::Torque12
        } else {
            MitPacking::Torque8Crc
        }
    }

    /// The MOVE-mode code of MIT (0x04, or 0x06 from S-V1.8-8).
    pub fn mit_move_mode(self) -> MoveMode {
        if self >= Self::new(1, 8, 8) {
            MoveMode::MitV188
        } else {
            MoveMode::Mit
        }
    }

    /// True when this firmware uses the 2° J2/J3 DH offset (S-V1.6-3 and later).
    pub fn uses_dh_offset(self) -> bool {
        self >= Self::new(1, 6, 3)
    }

    /// True before S-V1.7-3, whose MIT commands are negated on joints 1, 2, 4 and 6.
    pub fn mit_sign_flipped(self) -> bool {
        self < Self::new(1, 7, 3)
    }

    /// True up to S-V1.8-2, where joints 1–3 execute 4× the commanded MIT torque.
    pub fn mit_torque_x4_j123(self) -> bool {
        self <= Self::new(1, 8, 2)
    }
}

impl fmt::Display for FirmwareVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "S-V{}.{}-{}", self.major, self.minor, self.patch)
    }
}

/// The decoded 88-byte firmware reply.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct FirmwareInfo {
    /// Hardware version, e.g. `H-V1.2-1`.
    pub hardware: String,
    /// Motor ratio and batch.
    pub ratio: String,
    /// Node type, e.g. `ARM_MC`.
    pub node_type: String,
    /// Software version string, e.g. `S-V1.8-8`.
    pub software: String,
    /// Production date YYMMDD.
    pub date: String,
    /// Node number.
    pub node: String,
    /// The parsed software version (`None` if the string does not parse).
    pub version: Option<FirmwareVersion>,
}

fn ascii_field(buf: &[u8], at: usize, len: usize) -> String {
    let end = (at + len).min(buf.len());
    let field = buf.get(at..end).unwrap_or(&[]);
    let field: Vec<u8> = field.iter().copied().take_while(|b| *b != 0).collect();
    String::from_utf8_lossy(&field).into_owned()
}

impl FirmwareInfo {
    /// Parse an 88-byte reply. The software version is taken as the 8 bytes from `S-V`
    /// wherever it appears (as every SDK does), falling back to offset 60.
    pub fn parse(buf: &[u8]) -> Self {
        let software = match buf.windows(3).position(|w| w == b"S-V") {
            Some(at) => ascii_field(buf, at, 8),
            None => ascii_field(buf, 60, 8),
        };
        Self {
            hardware: ascii_field(buf, 0, 8),
            ratio: ascii_field(buf, 16, 2),
            node_type: ascii_field(buf, 32, 6),
            version: FirmwareVersion::parse(&software),
            software,
            date: ascii_field(buf, 68, 6),
            node: ascii_field(buf, 76, 2),
        }
    }
}

/// Collects 0x4AF reply frames until the 88-byte reply is complete.
#[derive(Debug, Clone, Default)]
pub struct FirmwareAssembler {
    buf: Vec<u8>,
}

impl FirmwareAssembler {
    /// An empty assembler.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forget a partial reply (call when sending a query).
    pub fn reset(&mut self) {
        self.buf.clear();
    }

    /// Add one part; returns the reply once 88 bytes have arrived. A part that starts with
    /// `H-V` starts a new reply (resynchronises after a partial one).
    pub fn push(&mut self, part: &FirmwarePart) -> Option<FirmwareInfo> {
        let bytes = part.bytes();
        if bytes.starts_with(b"H-V") {
            self.buf.clear();
        }
        self.buf.extend_from_slice(bytes);
        if self.buf.len() >= FIRMWARE_REPLY_LEN {
            let info = FirmwareInfo::parse(&self.buf[..FIRMWARE_REPLY_LEN]);
            self.buf.clear();
            return Some(info);
        }
        None
    }

    /// Bytes collected so far.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_parse_and_order() {
        assert_eq!(
            FirmwareVersion::parse("S-V1.8-8"),
            Some(FirmwareVersion::new(1, 8, 8))
        );
        assert_eq!(
            FirmwareVersion::parse("1.6-3\0"),
            Some(FirmwareVersion::new(1, 6, 3))
        );
        assert_eq!(FirmwareVersion::parse("S-V1.8"), None);
        assert_eq!(FirmwareVersion::parse("S-Vx.8-8"), None);
        let old = FirmwareVersion::new(1, 7, 2);
        assert!(old.mit_sign_flipped() && old.mit_torque_x4_j123() && old.uses_dh_offset());
        assert_eq!(
            FirmwareVersion::new(1, 8, 7).mit_packing(),
            MitPacking::Torque8Crc
        );
        assert_eq!(
            FirmwareVersion::new(1, 8, 8).mit_move_mode(),
            MoveMode::MitV188
        );
        assert_eq!(FirmwareVersion::new(1, 8, 8).to_string(), "S-V1.8-8");
    }

    #[test]
    fn assembler_resynchronises_on_a_new_reply() {
        let mut buf = [0u8; 88];
        buf[..8].copy_from_slice(b"H-V1.2-1");
        buf[60..68].copy_from_slice(b"S-V1.8-2");
        let part = |k: usize| {
            let mut data = [0u8; 8];
            data.copy_from_slice(&buf[k * 8..k * 8 + 8]);
            FirmwarePart { data, len: 8 }
        };
        let mut assembler = FirmwareAssembler::new();
        // The tail of an earlier reply, then a complete one.
        for k in 7..11 {
            assert!(assembler.push(&part(k)).is_none());
        }
        let mut done = None;
        for k in 0..11 {
            done = assembler.push(&part(k));
        }
        let info = done.expect("complete");
        assert_eq!(info.version, Some(FirmwareVersion::new(1, 8, 2)));
        assert_eq!(assembler.pending(), 0);
    }
}
