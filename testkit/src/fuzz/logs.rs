//! Capture readers of the bus crate: candump `-L` logs and pcap files.

use std::time::Duration;

use bus::candump::{format_line, parse_line, parse_log};
use bus::pcap::{parse_capture, PcapWriter};
use bus::ReceivedFrame;

/// Arbitrary text through the candump log reader.
///
/// Asserts: no panic; every entry that reads writes back (`format_line`) to a line that reads
/// to the same interface and frame, with the timestamp cut to microseconds (the writer's
/// resolution).
pub fn candump_reader(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    // The log as a whole, and each line alone (a bad line stops the whole-log reader).
    let entries: Vec<_> = match parse_log(&text) {
        Ok(entries) => entries,
        Err(e) => {
            let _ = e.to_string();
            text.lines()
                .filter_map(|l| parse_line(l.trim()).ok())
                .collect()
        }
    };
    for entry in entries {
        let received = ReceivedFrame {
            frame: entry.frame,
            timestamp: entry.timestamp,
        };
        let line = format_line(&entry.iface, &received);
        let again = parse_line(&line)
            .unwrap_or_else(|e| panic!("written line {line:?} does not read back: {e}"));
        assert_eq!(again.frame, entry.frame, "{line}");
        assert_eq!(again.iface, entry.iface, "{line}");
        let micros = Duration::new(
            entry.timestamp.as_secs(),
            entry.timestamp.subsec_micros() * 1000,
        );
        assert_eq!(again.timestamp, micros, "{line}");
    }
}

/// Arbitrary bytes through the pcap capture reader.
///
/// Asserts: no panic; a capture that reads writes back (`PcapWriter`) to bytes that read to
/// the same frames, and the same timestamps while they fit pcap's 32-bit seconds.
pub fn pcap_reader(data: &[u8]) {
    let frames = match parse_capture(data) {
        Ok(frames) => frames,
        Err(e) => {
            let _ = e.to_string();
            return;
        }
    };
    let mut writer = PcapWriter::new(Vec::new()).expect("writing to memory");
    for f in &frames {
        writer.write(f).expect("writing to memory");
    }
    let bytes = writer.finish().expect("writing to memory");
    let again = parse_capture(&bytes).expect("a written capture reads back");
    // pcap stores 32-bit seconds: the writer wraps later times (documented). The reader also
    // carries a microsecond field of 10⁶ or more into the seconds, which can pass 2³² s.
    let fits = |f: &ReceivedFrame| f.timestamp.as_secs() <= u64::from(u32::MAX);
    if frames.iter().all(fits) {
        assert_eq!(again, frames);
    } else {
        let frames_only = |v: &[ReceivedFrame]| v.iter().map(|f| f.frame).collect::<Vec<_>>();
        assert_eq!(frames_only(&again), frames_only(&frames));
    }
}
