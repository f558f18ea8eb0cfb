//! pcapng capture files of several CAN buses: one interface description per bus, named as the
//! bus is (`can0` …), so Wireshark and tshark show each frame's bus (`frame.interface_name`).
//!
//! Little-endian, one section; each interface `LINKTYPE_CAN_SOCKETCAN` with the default
//! microsecond timestamps; each frame an enhanced packet block holding the same SocketCAN
//! packet as [`crate::pcap`] (16 bytes classic, 72 bytes CAN FD, read back as that module
//! reads them). A capture split into several files is joined by
//! dropping the first [`header_len`] bytes (section and interfaces) of every file but the first.

use std::io::{self, Write};
use std::time::Duration;

use crate::pcap::{decode_packet, Packet, PcapError, FD_PACKET_LEN, LINKTYPE_CAN_SOCKETCAN};
use crate::ReceivedFrame;

const SECTION_HEADER: u32 = 0x0A0D_0D0A;
const BYTE_ORDER_MAGIC: u32 = 0x1A2B_3C4D;
const INTERFACE_DESCRIPTION: u32 = 1;
const ENHANCED_PACKET: u32 = 6;
/// Option code of an interface's name.
const IF_NAME: u16 = 2;
/// Largest packet a reader should expect; comfortably above a CAN frame.
const SNAPLEN: u32 = 65_535;
/// An enhanced packet block without options: 32 bytes and the packet.
const PACKET_BLOCK_OVERHEAD: usize = 32;

/// `len` rounded up to the 32-bit boundary pcapng blocks keep.
fn padded(len: usize) -> usize {
    len.div_ceil(4) * 4
}

fn section_header() -> Vec<u8> {
    let mut block = Vec::with_capacity(28);
    block.extend(SECTION_HEADER.to_le_bytes());
    block.extend(28u32.to_le_bytes());
    block.extend(BYTE_ORDER_MAGIC.to_le_bytes());
    block.extend(1u16.to_le_bytes()); // version major
    block.extend(0u16.to_le_bytes()); // version minor
    block.extend((-1i64).to_le_bytes()); // section length: not given
    block.extend(28u32.to_le_bytes());
    block
}

fn interface_description(name: &str) -> Vec<u8> {
    let name_len = name.len().min(usize::from(u16::MAX));
    let total = 20 + 4 + padded(name_len) + 4;
    let mut block = Vec::with_capacity(total);
    block.extend(INTERFACE_DESCRIPTION.to_le_bytes());
    // A bus name is short (an interface name); the limit above keeps the casts exact.
    block.extend((total as u32).to_le_bytes());
    block.extend((LINKTYPE_CAN_SOCKETCAN as u16).to_le_bytes());
    block.extend(0u16.to_le_bytes()); // reserved
    block.extend(SNAPLEN.to_le_bytes());
    block.extend(IF_NAME.to_le_bytes());
    block.extend((name_len as u16).to_le_bytes());
    block.extend(&name.as_bytes()[..name_len]);
    block.resize(block.len() + padded(name_len) - name_len, 0);
    block.extend([0u8; 4]); // end of options
    block.extend((total as u32).to_le_bytes());
    block
}

/// Size of what [`PcapngWriter::new`] writes first for `interfaces`.
pub fn header_len(interfaces: &[&str]) -> usize {
    section_header().len()
        + interfaces
            .iter()
            .map(|name| interface_description(name).len())
            .sum::<usize>()
}

/// Writes frames of several buses to a pcapng file.
#[derive(Debug)]
pub struct PcapngWriter<W: Write> {
    out: W,
    interfaces: u32,
}

impl<W: Write> PcapngWriter<W> {
    /// Write the section header and one interface per name in `interfaces` (frames name
    /// their interface by its index in this list).
    pub fn new(mut out: W, interfaces: &[&str]) -> io::Result<Self> {
        out.write_all(&section_header())?;
        for name in interfaces {
            out.write_all(&interface_description(name))?;
        }
        Ok(Self {
            out,
            interfaces: u32::try_from(interfaces.len()).unwrap_or(u32::MAX),
        })
    }

    /// Append one frame seen on interface `interface` (an index into the names given).
    pub fn write(&mut self, interface: u32, received: &ReceivedFrame) -> io::Result<()> {
        if interface >= self.interfaces {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "interface {interface} of a capture of {} interfaces",
                    self.interfaces
                ),
            ));
        }
        // Microseconds since the epoch fit 64 bits for the next 500,000 years.
        let micros = received.timestamp.as_micros() as u64;
        let packet = Packet::of(&received.frame);
        let packet = packet.as_bytes();
        // 16 or 72 bytes: already a multiple of four, no padding.
        let block_len = PACKET_BLOCK_OVERHEAD + packet.len();
        let len = block_len as u32;
        let mut block = [0u8; PACKET_BLOCK_OVERHEAD + FD_PACKET_LEN];
        block[0..4].copy_from_slice(&ENHANCED_PACKET.to_le_bytes());
        block[4..8].copy_from_slice(&len.to_le_bytes());
        block[8..12].copy_from_slice(&interface.to_le_bytes());
        block[12..16].copy_from_slice(&((micros >> 32) as u32).to_le_bytes());
        block[16..20].copy_from_slice(&(micros as u32).to_le_bytes());
        block[20..24].copy_from_slice(&(packet.len() as u32).to_le_bytes()); // captured
        block[24..28].copy_from_slice(&(packet.len() as u32).to_le_bytes()); // original
        block[28..28 + packet.len()].copy_from_slice(packet);
        block[28 + packet.len()..block_len].copy_from_slice(&len.to_le_bytes());
        self.out.write_all(&block[..block_len])
    }

    /// Push buffered blocks to the underlying sink.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The sink being written.
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// Flush and hand back the sink; the capture is complete.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// A pcapng capture read back: its interfaces' names and every frame with its interface.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Capture {
    /// Interface names, by index (empty for an interface without a name).
    pub interfaces: Vec<String>,
    /// Frames in file order, each with the index of its interface.
    pub frames: Vec<(u32, ReceivedFrame)>,
}

fn u32_at(bytes: &[u8], offset: usize) -> Result<u32, PcapError> {
    bytes
        .get(offset..offset + 4)
        .and_then(|s| s.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or(PcapError::Truncated { offset })
}

fn u16_at(bytes: &[u8], offset: usize) -> Result<u16, PcapError> {
    bytes
        .get(offset..offset + 2)
        .and_then(|s| s.try_into().ok())
        .map(u16::from_le_bytes)
        .ok_or(PcapError::Truncated { offset })
}

/// The name option of an interface description block starting at `start` (`end` exclusive of
/// its trailing length).
fn interface_name(bytes: &[u8], mut offset: usize, end: usize) -> Result<String, PcapError> {
    while offset + 4 <= end {
        let code = u16_at(bytes, offset)?;
        let len = usize::from(u16_at(bytes, offset + 2)?);
        if code == 0 {
            break;
        }
        // An option ends inside its block: past `end` lie the next block's bytes.
        let value = bytes
            .get(offset + 4..offset + 4 + len)
            .filter(|_| offset + 4 + len <= end)
            .ok_or(PcapError::Truncated { offset: offset + 4 })?;
        if code == IF_NAME {
            return Ok(String::from_utf8_lossy(value).into_owned());
        }
        offset += 4 + padded(len);
    }
    Ok(String::new())
}

/// Read back a little-endian capture as [`PcapngWriter`] writes it; blocks of other types are
/// skipped.
pub fn parse_capture(bytes: &[u8]) -> Result<Capture, PcapError> {
    let kind = u32_at(bytes, 0)?;
    let magic = u32_at(bytes, 8)?;
    if kind != SECTION_HEADER || magic != BYTE_ORDER_MAGIC {
        return Err(PcapError::BadMagic { magic: kind });
    }
    let mut capture = Capture::default();
    let mut offset = 0;
    while offset < bytes.len() {
        let kind = u32_at(bytes, offset)?;
        let len = u32_at(bytes, offset + 4)? as usize;
        if len < 12 || !len.is_multiple_of(4) || offset + len > bytes.len() {
            return Err(PcapError::Truncated { offset });
        }
        match kind {
            INTERFACE_DESCRIPTION => {
                let link = u32::from(u16_at(bytes, offset + 8)?);
                if link != LINKTYPE_CAN_SOCKETCAN {
                    return Err(PcapError::WrongLinkType(link));
                }
                let name = interface_name(bytes, offset + 16, offset + len - 4)?;
                capture.interfaces.push(name);
            }
            ENHANCED_PACKET => {
                let interface = u32_at(bytes, offset + 8)?;
                let micros = (u64::from(u32_at(bytes, offset + 12)?) << 32)
                    | u64::from(u32_at(bytes, offset + 16)?);
                let captured = u32_at(bytes, offset + 20)? as usize;
                let start = offset + 28;
                // The packet lies inside its block, before the block's trailing length: a
                // captured length past that would read the next block's bytes as data.
                let block_end = offset + len - 4;
                let packet = bytes
                    .get(start..start.saturating_add(captured))
                    .filter(|_| start.saturating_add(captured) <= block_end)
                    .ok_or(PcapError::Truncated { offset: start })?;
                let frame = decode_packet(packet, start)?;
                capture.frames.push((
                    interface,
                    ReceivedFrame {
                        frame,
                        timestamp: Duration::from_micros(micros),
                    },
                ));
            }
            _ => {}
        }
        offset += len;
    }
    Ok(capture)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::PACKET_LEN;
    use crate::CanFrame;

    fn received(id: u16, micros: u64) -> ReceivedFrame {
        ReceivedFrame {
            frame: CanFrame::standard(id, &[id as u8, 2, 3]).unwrap(),
            timestamp: Duration::from_micros(micros),
        }
    }

    #[test]
    fn frames_keep_their_bus_and_time_and_read_back() {
        let names = ["can0", "left_leg"];
        let mut writer = PcapngWriter::new(Vec::new(), &names).unwrap();
        writer
            .write(1, &received(0x101, 1_700_000_000_123_456))
            .unwrap();
        writer
            .write(0, &received(0x102, 1_700_000_000_123_999))
            .unwrap();
        let extended = ReceivedFrame {
            frame: CanFrame::extended(0x0200_FD01, &[9; 8]).unwrap(),
            timestamp: Duration::from_micros(5),
        };
        writer.write(1, &extended).unwrap();
        let bytes = writer.finish().unwrap();
        assert_eq!(
            bytes.len(),
            header_len(&names) + 3 * (PACKET_BLOCK_OVERHEAD + PACKET_LEN)
        );
        let capture = parse_capture(&bytes).unwrap();
        assert_eq!(capture.interfaces, ["can0", "left_leg"]);
        assert_eq!(
            capture.frames,
            [
                (1, received(0x101, 1_700_000_000_123_456)),
                (0, received(0x102, 1_700_000_000_123_999)),
                (1, extended)
            ]
        );
    }

    #[test]
    fn a_frame_on_an_interface_not_described_is_refused() {
        let mut writer = PcapngWriter::new(Vec::new(), &["can0"]).unwrap();
        let error = writer.write(1, &received(1, 0)).unwrap_err();
        assert!(
            error.to_string().contains("interface 1 of a capture of 1"),
            "{error}"
        );
    }

    /// A packet whose captured length runs past its own block is refused: read as it claims,
    /// it would take the next block's header for frame data.
    #[test]
    fn a_packet_claiming_more_than_its_block_holds_is_refused() {
        let names = ["can0"];
        let mut writer = PcapngWriter::new(Vec::new(), &names).unwrap();
        writer.write(0, &received(0x123, 1)).unwrap();
        writer.write(0, &received(0x124, 2)).unwrap();
        let mut bytes = writer.finish().unwrap();
        let first = header_len(&names);
        let claimed = (PACKET_LEN + 16) as u32;
        bytes[first + 20..first + 24].copy_from_slice(&claimed.to_le_bytes());
        assert!(
            matches!(
                parse_capture(&bytes),
                Err(PcapError::Truncated { offset }) if offset == first + 28
            ),
            "{:?}",
            parse_capture(&bytes)
        );
    }

    /// An interface's name option that claims to run past its block is refused likewise.
    #[test]
    fn an_interface_name_longer_than_its_block_is_refused() {
        let names = ["can0"];
        let mut writer = PcapngWriter::new(Vec::new(), &names).unwrap();
        writer.write(0, &received(0x123, 1)).unwrap();
        let mut bytes = writer.finish().unwrap();
        // The name option follows the section header and the description's 16 fixed bytes;
        // 12 bytes of name would take in the end-of-options and the block's trailing length.
        let option = section_header().len() + 16;
        assert_eq!(u16_at(&bytes, option).unwrap(), IF_NAME);
        bytes[option + 2..option + 4].copy_from_slice(&12u16.to_le_bytes());
        assert!(matches!(
            parse_capture(&bytes),
            Err(PcapError::Truncated { .. })
        ));
    }

    #[test]
    fn fd_frames_keep_their_flags_and_length_in_pcapng() {
        let names = ["can0", "can1"];
        let fd = ReceivedFrame {
            frame: CanFrame::fd(
                crate::CanId::Standard(0x321),
                &[0x42; 48],
                crate::FdFlags {
                    brs: true,
                    esi: true,
                },
            )
            .unwrap(),
            timestamp: Duration::from_micros(1_700_000_000_000_001),
        };
        let mut writer = PcapngWriter::new(Vec::new(), &names).unwrap();
        writer.write(1, &fd).unwrap();
        writer.write(0, &received(0x100, 2)).unwrap();
        let bytes = writer.finish().unwrap();
        let first = header_len(&names);
        assert_eq!(
            bytes.len(),
            first + (PACKET_BLOCK_OVERHEAD + FD_PACKET_LEN) + (PACKET_BLOCK_OVERHEAD + PACKET_LEN)
        );
        // Block length, captured and original lengths of the CAN FD frame's block.
        assert_eq!(u32_at(&bytes, first + 4).unwrap(), 104);
        assert_eq!(u32_at(&bytes, first + 20).unwrap(), 72);
        assert_eq!(u32_at(&bytes, first + 24).unwrap(), 72);
        assert_eq!(u32_at(&bytes, first + 100).unwrap(), 104);
        let capture = parse_capture(&bytes).unwrap();
        assert_eq!(capture.frames, [(1, fd), (0, received(0x100, 2))]);
        assert_eq!(
            capture.frames[0].1.frame.fd_flags(),
            Some(crate::FdFlags {
                brs: true,
                esi: true
            })
        );
    }
}
