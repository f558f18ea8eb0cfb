//! pcap capture files with `LINKTYPE_CAN_SOCKETCAN` (227), as Wireshark and tshark read them.
//!
//! Classic pcap with microsecond timestamps, written little-endian (the magic number tells
//! readers the byte order). Each packet is a SocketCAN frame: the identifier in network byte
//! order with `CAN_EFF_FLAG` (0x8000_0000) set for extended identifiers, the data length, a
//! flags byte, two reserved bytes, then the data (unused bytes zero):
//!
//! - a classic frame is the 16-byte `struct can_frame`: flags zero, eight data bytes;
//! - a CAN FD frame is the 72-byte `struct canfd_frame`: flags `CANFD_FDF` (0x04) with
//!   `CANFD_BRS` (0x01) and `CANFD_ESI` (0x02) as the frame has them, 64 data bytes.
//!
//! Reading, a 72-byte packet is a CAN FD frame whose length must be a CAN FD length (anything
//! else is [`PcapError::BadFdLength`], naming where); a 16-byte packet is classic unless its
//! flags byte has `CANFD_FDF`, which marks a CAN FD frame of at most eight bytes (the
//! "dual use" the kernel's `can.h` describes).

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use crate::{is_fd_data_len, CanFrame, CanId, FdFlags, ReceivedFrame, MAX_DATA_LEN};

/// pcap link type of SocketCAN frames.
pub const LINKTYPE_CAN_SOCKETCAN: u32 = 227;
/// Set in the identifier word of an extended frame.
pub const CAN_EFF_FLAG: u32 = 0x8000_0000;
/// Size of the SocketCAN packet of a classic frame in the capture.
pub const PACKET_LEN: usize = 16;
/// Size of the SocketCAN packet of a CAN FD frame in the capture.
pub const FD_PACKET_LEN: usize = 72;
/// Flags byte (offset 5) of a CAN FD packet: the frame is CAN FD.
pub const CANFD_FDF: u8 = 0x04;
/// Flags byte of a CAN FD packet: bit-rate switch.
pub const CANFD_BRS: u8 = 0x01;
/// Flags byte of a CAN FD packet: error state indicator.
pub const CANFD_ESI: u8 = 0x02;
/// Size of the global header at the start of every capture file: a capture split into
/// several files is joined by dropping this header from every file but the first.
pub const GLOBAL_HEADER_LEN: usize = 24;
/// Size of each packet's record header (seconds, microseconds, two lengths).
pub const RECORD_HEADER_LEN: usize = 16;
/// Magic number of microsecond-resolution pcap files.
const MAGIC_MICROS: u32 = 0xA1B2_C3D4;
/// Largest packet a reader should expect; comfortably above a CAN frame.
const SNAPLEN: u32 = 65_535;

/// The SocketCAN packet of any frame: 16 bytes for a classic frame, 72 for a CAN FD one.
#[derive(Clone, Copy)]
pub(crate) struct Packet {
    bytes: [u8; FD_PACKET_LEN],
    len: usize,
}

impl Packet {
    pub(crate) fn of(frame: &CanFrame) -> Self {
        let id_word = match frame.id() {
            CanId::Standard(id) => u32::from(id),
            CanId::Extended(id) => id | CAN_EFF_FLAG,
        };
        let mut bytes = [0u8; FD_PACKET_LEN];
        bytes[..4].copy_from_slice(&id_word.to_be_bytes());
        // Cannot truncate: at most 64.
        bytes[4] = frame.len() as u8;
        if let Some(flags) = frame.fd_flags() {
            bytes[5] = CANFD_FDF | flags.bits();
        }
        bytes[8..8 + frame.len()].copy_from_slice(frame.data());
        let len = if frame.is_fd() {
            FD_PACKET_LEN
        } else {
            PACKET_LEN
        };
        Self { bytes, len }
    }

    pub(crate) fn as_bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

/// The 16-byte SocketCAN encoding of a classic frame. A CAN FD frame's packet is
/// [`encode_fd_packet`]; given one, this returns that packet's first 16 bytes (identifier,
/// length, flags and the first eight data bytes), which do not make a packet of their own.
pub fn encode_packet(frame: &CanFrame) -> [u8; PACKET_LEN] {
    let mut packet = [0u8; PACKET_LEN];
    packet.copy_from_slice(&Packet::of(frame).bytes[..PACKET_LEN]);
    packet
}

/// The 72-byte SocketCAN encoding of a CAN FD frame (`None` for a classic frame, whose packet
/// is [`encode_packet`]'s 16 bytes).
pub fn encode_fd_packet(frame: &CanFrame) -> Option<[u8; FD_PACKET_LEN]> {
    frame.is_fd().then(|| Packet::of(frame).bytes)
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

    /// Append one frame (16 bytes classic, 72 CAN FD). Timestamps beyond the year 2106 wrap
    /// (pcap stores 32-bit seconds).
    pub fn write(&mut self, received: &ReceivedFrame) -> io::Result<()> {
        let packet = Packet::of(&received.frame);
        let packet = packet.as_bytes();
        // Truncation is the format's limit, documented above.
        let secs = received.timestamp.as_secs() as u32;
        self.out.write_all(&secs.to_le_bytes())?;
        self.out
            .write_all(&received.timestamp.subsec_micros().to_le_bytes())?;
        // Cannot truncate: 16 or 72.
        let len = packet.len() as u32;
        self.out.write_all(&len.to_le_bytes())?; // captured length
        self.out.write_all(&len.to_le_bytes())?; // original length
        self.out.write_all(packet)
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
    /// A packet is not a valid CAN frame (16 bytes) or CAN FD frame (72 bytes).
    #[error("packet at byte {offset} is not a CAN frame (16 bytes) or CAN FD frame (72 bytes)")]
    BadPacket {
        /// Where the packet starts.
        offset: usize,
    },
    /// A CAN FD packet claims a payload length no CAN FD frame has.
    #[error(
        "packet at byte {offset} claims a CAN FD payload of {len} bytes; a CAN FD frame has \
         0-8, 12, 16, 20, 24, 32, 48 or 64"
    )]
    BadFdLength {
        /// Where the packet starts.
        offset: usize,
        /// The length it claims.
        len: usize,
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
        let frame = decode_packet(packet, start)?;
        frames.push(ReceivedFrame {
            frame,
            timestamp: Duration::from_secs(u64::from(secs))
                + Duration::from_micros(u64::from(micros)),
        });
        offset = start + captured;
    }
    Ok(frames)
}

/// The frame of a SocketCAN packet starting at byte `offset` of the capture (for the error).
pub(crate) fn decode_packet(packet: &[u8], offset: usize) -> Result<CanFrame, PcapError> {
    let bad = || PcapError::BadPacket { offset };
    let fd = match packet.len() {
        FD_PACKET_LEN => true,
        PACKET_LEN => packet[5] & CANFD_FDF != 0,
        _ => return Err(bad()),
    };
    let id_word = u32::from_be_bytes([packet[0], packet[1], packet[2], packet[3]]);
    // Other flags in the word (RTR, error) leave it out of range: not a data frame.
    let id = if id_word & CAN_EFF_FLAG != 0 {
        CanId::extended(id_word & !CAN_EFF_FLAG).ok()
    } else {
        u16::try_from(id_word)
            .ok()
            .and_then(|id| CanId::standard(id).ok())
    }
    .ok_or_else(bad)?;
    let len = usize::from(packet[4]);
    if fd {
        if !is_fd_data_len(len) {
            return Err(PcapError::BadFdLength { offset, len });
        }
        // A 16-byte packet holds at most eight data bytes.
        let data = packet.get(8..8 + len).ok_or_else(bad)?;
        CanFrame::fd(id, data, FdFlags::from_bits(packet[5])).map_err(|_| bad())
    } else {
        let data = packet.get(8..8 + len).filter(|_| len <= MAX_DATA_LEN);
        CanFrame::new(id, data.ok_or_else(bad)?).map_err(|_| bad())
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

    fn fd(id: CanId, len: usize, brs: bool, esi: bool) -> CanFrame {
        let data: Vec<u8> = (0..len).map(|i| 0x80 | i as u8).collect();
        CanFrame::fd(id, &data, FdFlags { brs, esi }).unwrap()
    }

    #[test]
    fn fd_packets_are_72_bytes_with_the_fdf_flag() {
        let frame = fd(CanId::Standard(0x2A1), 12, true, false);
        let packet = encode_fd_packet(&frame).unwrap();
        assert_eq!(&packet[..8], &[0, 0, 0x02, 0xA1, 12, 0x04 | 0x01, 0, 0]);
        assert_eq!(&packet[8..20], frame.data());
        assert!(packet[20..].iter().all(|&b| b == 0));
        let frame = fd(CanId::Extended(0x0200_FD01), 64, false, true);
        let packet = encode_fd_packet(&frame).unwrap();
        assert_eq!(
            &packet[..8],
            &[0x82, 0x00, 0xFD, 0x01, 64, 0x04 | 0x02, 0, 0]
        );
        assert_eq!(&packet[8..], frame.data());
        assert_eq!(encode_fd_packet(&CanFrame::standard(1, &[]).unwrap()), None);
    }

    #[test]
    fn fd_and_classic_frames_round_trip_through_a_capture() {
        let mut frames = Vec::new();
        for (i, &len) in crate::FD_DATA_LENS.iter().enumerate() {
            let id = if i % 2 == 0 {
                CanId::Standard(0x700 + i as u16)
            } else {
                CanId::Extended(0x1FFF_FF00 + i as u32)
            };
            frames.push(ReceivedFrame {
                frame: fd(id, len, i % 2 == 0, i % 3 == 0),
                timestamp: Duration::new(1_700_000_000, 1000 * i as u32),
            });
            frames.push(ReceivedFrame {
                frame: CanFrame::new(id, &[i as u8; 3]).unwrap(),
                timestamp: Duration::new(1_700_000_001, 1000 * i as u32),
            });
        }
        let mut writer = PcapWriter::new(Vec::new()).unwrap();
        for frame in &frames {
            writer.write(frame).unwrap();
        }
        let bytes = writer.finish().unwrap();
        assert_eq!(
            bytes.len(),
            GLOBAL_HEADER_LEN + 32 * RECORD_HEADER_LEN + 16 * FD_PACKET_LEN + 16 * PACKET_LEN
        );
        // The first record: a 72-byte packet, both lengths saying so.
        assert_eq!(&bytes[32..36], &72u32.to_le_bytes());
        assert_eq!(&bytes[36..40], &72u32.to_le_bytes());
        let read = parse_capture(&bytes).unwrap();
        assert_eq!(read, frames);
        for (got, want) in read.iter().zip(&frames) {
            assert_eq!(got.frame.fd_flags(), want.frame.fd_flags());
        }
    }

    /// A capture with one record holding `packet`.
    fn capture_of(packet: &[u8]) -> Vec<u8> {
        let mut bytes = PcapWriter::new(Vec::new()).unwrap().finish().unwrap();
        bytes.extend(7u32.to_le_bytes());
        bytes.extend(0u32.to_le_bytes());
        bytes.extend((packet.len() as u32).to_le_bytes());
        bytes.extend((packet.len() as u32).to_le_bytes());
        bytes.extend(packet);
        bytes
    }

    #[test]
    fn a_packet_claiming_a_bad_fd_length_is_refused_with_where_and_what() {
        let frame = fd(CanId::Standard(0x123), 64, true, false);
        let mut packet = encode_fd_packet(&frame).unwrap();
        for bad in [9u8, 13, 63, 65, 255] {
            packet[4] = bad;
            let error = parse_capture(&capture_of(&packet)).unwrap_err();
            assert_eq!(
                error,
                PcapError::BadFdLength {
                    offset: GLOBAL_HEADER_LEN + RECORD_HEADER_LEN,
                    len: usize::from(bad)
                }
            );
            assert_eq!(
                error.to_string(),
                format!(
                    "packet at byte 40 claims a CAN FD payload of {bad} bytes; a CAN FD frame \
                     has 0-8, 12, 16, 20, 24, 32, 48 or 64"
                )
            );
        }
        // A 72-byte packet is CAN FD by its length even without the FDF flag (older
        // captures), and reads its flags.
        packet[4] = 20;
        packet[5] = 0x01;
        let read = parse_capture(&capture_of(&packet)).unwrap();
        assert!(read[0].frame.is_fd() && read[0].frame.brs() && read[0].frame.len() == 20);
    }

    #[test]
    fn a_16_byte_packet_with_fdf_is_a_short_fd_frame() {
        let classic = CanFrame::standard(0x123, &[1, 2, 3]).unwrap();
        let mut packet = encode_packet(&classic);
        packet[5] = CANFD_FDF | CANFD_ESI;
        let read = parse_capture(&capture_of(&packet)).unwrap();
        assert_eq!(
            read[0].frame,
            CanFrame::fd(
                CanId::Standard(0x123),
                &[1, 2, 3],
                FdFlags {
                    brs: false,
                    esi: true
                }
            )
            .unwrap()
        );
        // One claiming more than the 8 bytes it holds is refused, not read past its end.
        packet[4] = 12;
        assert_eq!(
            parse_capture(&capture_of(&packet)),
            Err(PcapError::BadPacket { offset: 40 })
        );
        packet[4] = 9;
        assert_eq!(
            parse_capture(&capture_of(&packet)),
            Err(PcapError::BadFdLength { offset: 40, len: 9 })
        );
        // Other packet sizes are not frames.
        assert_eq!(
            parse_capture(&capture_of(&[0; 40])),
            Err(PcapError::BadPacket { offset: 40 })
        );
    }
}
