//! pcap capture files with `LINKTYPE_CAN_SOCKETCAN` (227), as Wireshark and tshark read them.
//!
//! Classic pcap with microsecond timestamps, written little-endian (the magic number tells
//! readers the byte order). Each packet is the 16-byte SocketCAN frame: the identifier in
//! network byte order with `CAN_EFF_FLAG` (0x8000_0000) set for extended identifiers, the data
//! length, three bytes of padding and eight data bytes (unused ones zero).

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use crate::{CanFrame, CanId, ReceivedFrame, MAX_DATA_LEN};

/// pcap link type of SocketCAN frames.
pub const LINKTYPE_CAN_SOCKETCAN: u32 = 227;
/// Set in the identifier word of an extended frame.
pub const CAN_EFF_FLAG: u32 = 0x8000_0000;
/// Size of one SocketCAN packet in the capture.
pub const PACKET_LEN: usize = 16;
/// Size of the global header at the start of every capture file: a capture split into
/// several files is joined by dropping this header from every file but the first.
pub const GLOBAL_HEADER_LEN: usize = 24;
/// Size of each packet's record header (seconds, microseconds, two lengths).
pub const RECORD_HEADER_LEN: usize = 16;
/// Magic number of microsecond-resolution pcap files.
const MAGIC_MICROS: u32 = 0xA1B2_C3D4;
/// Largest packet a reader should expect; comfortably above a CAN frame.
const SNAPLEN: u32 = 65_535;

/// The 16-byte SocketCAN encoding of a frame.
pub fn encode_packet(frame: &CanFrame) -> [u8; PACKET_LEN] {
    let id_word = match frame.id() {
        CanId::Standard(id) => u32::from(id),
        CanId::Extended(id) => id | CAN_EFF_FLAG,
    };
    let mut packet = [0u8; PACKET_LEN];
    packet[..4].copy_from_slice(&id_word.to_be_bytes());
    // Cannot truncate: at most 8.
    packet[4] = frame.len() as u8;
    packet[8..8 + frame.len()].copy_from_slice(frame.data());
    packet
}

/// Writes frames to a pcap file.
#[derive(Debug)]
pub struct PcapWriter<W: Write> {
    out: W,
}

impl PcapWriter<BufWriter<File>> {
    /// Create (or truncate) a capture file and write its header.
    pub fn create(path: impl AsRef<Path>) -> io::Result<Self> {
        Self::new(BufWriter::new(File::create(path)?))
    }
}

impl<W: Write> PcapWriter<W> {
    /// Write the pcap global header to `out`.
    pub fn new(mut out: W) -> io::Result<Self> {
        out.write_all(&MAGIC_MICROS.to_le_bytes())?;
        out.write_all(&2u16.to_le_bytes())?; // version major
        out.write_all(&4u16.to_le_bytes())?; // version minor
        out.write_all(&0i32.to_le_bytes())?; // timezone offset: timestamps are UTC
        out.write_all(&0u32.to_le_bytes())?; // timestamp accuracy, unused by convention
        out.write_all(&SNAPLEN.to_le_bytes())?;
        out.write_all(&LINKTYPE_CAN_SOCKETCAN.to_le_bytes())?;
        Ok(Self { out })
    }

    /// Append one frame. Timestamps beyond the year 2106 wrap (pcap stores 32-bit seconds).
    pub fn write(&mut self, received: &ReceivedFrame) -> io::Result<()> {
        let packet = encode_packet(&received.frame);
        // Truncation is the format's limit, documented above.
        let secs = received.timestamp.as_secs() as u32;
        self.out.write_all(&secs.to_le_bytes())?;
        self.out
            .write_all(&received.timestamp.subsec_micros().to_le_bytes())?;
        let len = PACKET_LEN as u32;
        self.out.write_all(&len.to_le_bytes())?; // captured length
        self.out.write_all(&len.to_le_bytes())?; // original length
        self.out.write_all(&packet)
    }

    /// Push buffered packets to the underlying sink.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The sink being written (e.g. to ask a counting writer how much has been written).
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// Flush and hand back the sink; the capture is complete.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Why a pcap capture could not be read back.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PcapError {
    /// The data ends inside a header or packet.
    #[error("capture truncated at byte {offset}")]
    Truncated {
        /// Where the missing data should have started.
        offset: usize,
    },
    /// Not a little-endian microsecond pcap file.
    #[error("not a little-endian microsecond pcap file (magic {magic:#010x})")]
    BadMagic {
        /// The magic number found.
        magic: u32,
    },
    /// The capture is not of SocketCAN frames.
    #[error("link type {0} is not LINKTYPE_CAN_SOCKETCAN (227)")]
    WrongLinkType(u32),
    /// A packet is not a valid classic CAN frame.
    #[error("packet at byte {offset} is not a classic CAN frame")]
    BadPacket {
        /// Where the packet starts.
        offset: usize,
    },
}

fn read_u32(bytes: &[u8], offset: usize) -> Result<u32, PcapError> {
    bytes
        .get(offset..offset + 4)
        .and_then(|slice| slice.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or(PcapError::Truncated { offset })
}

/// Read back a capture written by [`PcapWriter`] (little-endian, microseconds, link type 227).
pub fn parse_capture(bytes: &[u8]) -> Result<Vec<ReceivedFrame>, PcapError> {
    let magic = read_u32(bytes, 0)?;
    if magic != MAGIC_MICROS {
        return Err(PcapError::BadMagic { magic });
    }
    let link_type = read_u32(bytes, 20)?;
    if link_type != LINKTYPE_CAN_SOCKETCAN {
        return Err(PcapError::WrongLinkType(link_type));
    }
    let mut frames = Vec::new();
    let mut offset = GLOBAL_HEADER_LEN;
    while offset < bytes.len() {
        let secs = read_u32(bytes, offset)?;
        let micros = read_u32(bytes, offset + 4)?;
        let captured = read_u32(bytes, offset + 8)? as usize;
        let start = offset + RECORD_HEADER_LEN;
        let packet = bytes
            .get(start..start + captured)
            .ok_or(PcapError::Truncated { offset: start })?;
        let frame = decode_packet(packet).ok_or(PcapError::BadPacket { offset: start })?;
        frames.push(ReceivedFrame {
            frame,
            timestamp: Duration::from_secs(u64::from(secs))
                + Duration::from_micros(u64::from(micros)),
        });
        offset = start + captured;
    }
    Ok(frames)
}

/// The frame of a 16-byte SocketCAN packet, if it is one.
pub(crate) fn decode_packet(packet: &[u8]) -> Option<CanFrame> {
    if packet.len() != PACKET_LEN {
        return None;
    }
    let id_word = u32::from_be_bytes(packet[..4].try_into().ok()?);
    let len = usize::from(packet[4]);
    if len > MAX_DATA_LEN {
        return None;
    }
    let data = &packet[8..8 + len];
    if id_word & CAN_EFF_FLAG != 0 {
        CanFrame::extended(id_word & !CAN_EFF_FLAG, data).ok()
    } else {
        CanFrame::standard(u16::try_from(id_word).ok()?, data).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packets_carry_big_endian_ids_with_the_extended_flag() {
        let standard = CanFrame::standard(0x2A1, &[0xAA, 0xBB]).unwrap();
        assert_eq!(
            encode_packet(&standard),
            [0, 0, 0x02, 0xA1, 2, 0, 0, 0, 0xAA, 0xBB, 0, 0, 0, 0, 0, 0]
        );
        let extended = CanFrame::extended(0x0200_FD01, &[1; 8]).unwrap();
        assert_eq!(
            encode_packet(&extended),
            [0x82, 0x00, 0xFD, 0x01, 8, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1]
        );
    }

    #[test]
    fn header_and_records_have_the_documented_layout_and_round_trip() {
        let frames = [
            ReceivedFrame {
                frame: CanFrame::standard(0x123, &[1, 2, 3]).unwrap(),
                timestamp: Duration::new(1_700_000_000, 123_456_000),
            },
            ReceivedFrame {
                frame: CanFrame::extended(0x1FFF_FFFF, &[]).unwrap(),
                timestamp: Duration::new(1_700_000_001, 0),
            },
        ];
        let mut writer = PcapWriter::new(Vec::new()).unwrap();
        for frame in &frames {
            writer.write(frame).unwrap();
        }
        let bytes = writer.finish().unwrap();
        assert_eq!(bytes.len(), 24 + 2 * (16 + PACKET_LEN));
        assert_eq!(&bytes[..4], &[0xD4, 0xC3, 0xB2, 0xA1]);
        assert_eq!(&bytes[20..24], &227u32.to_le_bytes());
        assert_eq!(&bytes[24..28], &1_700_000_000u32.to_le_bytes());
        assert_eq!(&bytes[28..32], &123_456u32.to_le_bytes());
        assert_eq!(parse_capture(&bytes).unwrap(), frames);
        assert_eq!(
            parse_capture(&bytes[..bytes.len() - 1]),
            Err(PcapError::Truncated {
                offset: 24 + 16 + 16 + 16
            })
        );
    }
}
