//! Bus recordings through the bus crate's writers (into memory; the caller writes the file
//! atomically).

use bus::candump::CandumpWriter;
use bus::pcap::PcapWriter;
use bus::ReceivedFrame;

/// Interface name written in the candump log (`vcan0` so can-utils replays it as is).
const LOG_IFACE: &str = "vcan0";

/// The frames as a candump `-L` log.
pub(crate) fn candump_bytes(frames: &[ReceivedFrame]) -> std::io::Result<Vec<u8>> {
    let mut writer = CandumpWriter::new(Vec::new(), LOG_IFACE);
    for f in frames {
        writer.write(f)?;
    }
    writer.finish()
}

/// The frames as a pcap (LINKTYPE_CAN_SOCKETCAN).
pub(crate) fn pcap_bytes(frames: &[ReceivedFrame]) -> std::io::Result<Vec<u8>> {
    let mut writer = PcapWriter::new(Vec::new())?;
    for f in frames {
        writer.write(f)?;
    }
    writer.finish()
}
