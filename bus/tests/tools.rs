//! The recorders' files checked by the tools people open them with: can-utils (`log2asc`,
//! `asc2log`, `log2long`) and tshark. Each test first asks `testkit::tools::require` for its
//! programs: missing, it says in one line that it skipped and what to install (CI installs
//! them and sets `ARMHIL_REQUIRE_TOOLS=1`, which turns a missing program into a failure).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use bus::candump::{parse_log, read_log};
use bus::pcap::parse_capture;
use bus::recorder::{record_tap, Recorder};
use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::{CanBus, CanFrame, CanId, FdFlags, ReceivedFrame};
use testkit::tools::{require, ASC2LOG, LOG2ASC, LOG2LONG, TSHARK};

const EPOCH_S: u64 = 1_700_000_000;

fn scratch_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("armhil-bus-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn sample_frames() -> Vec<CanFrame> {
    vec![
        CanFrame::standard(0x2A1, &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77]).unwrap(),
        CanFrame::extended(0x0200_FD01, &[0xAB, 0xCD]).unwrap(),
        CanFrame::standard(0x007, &[]).unwrap(),
        CanFrame::extended(0x1FFF_FFFF, &[0xFF; 8]).unwrap(),
        CanFrame::standard(0x7FF, &[0x01]).unwrap(),
    ]
}

/// Classic and CAN FD frames: every flag combination, both identifier widths, short and long
/// payloads.
fn fd_sample_frames() -> Vec<CanFrame> {
    let fd = |id, data: &[u8], brs, esi| CanFrame::fd(id, data, FdFlags { brs, esi }).unwrap();
    let counting: Vec<u8> = (0..64).collect();
    vec![
        fd(CanId::Standard(0x123), &[0xAA, 0xBB, 0xCC], true, false),
        fd(CanId::Extended(0x1ABC_DEF0), &counting, true, true),
        CanFrame::standard(0x2A1, &[0x00, 0x11]).unwrap(),
        fd(CanId::Standard(0x7FF), &counting[..12], false, false),
        fd(CanId::Standard(0x010), &[], false, true),
        CanFrame::extended(0x0200_FD01, &[0xAB, 0xCD]).unwrap(),
    ]
}

/// Run a virtual bus (paused clock) carrying the sample frames, 1 ms apart, and record its tap
/// to `path`. Returns what the tap delivered.
fn record_virtual_run(path: &Path) -> Vec<ReceivedFrame> {
    record_frames(path, sample_frames())
}

/// Like [`record_virtual_run`] for any frames, on a bus that carries CAN FD (5 Mbit/s data).
fn record_frames(path: &Path, frames: Vec<CanFrame>) -> Vec<ReceivedFrame> {
    let count = frames.len() as u64;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .unwrap();
    runtime.block_on(async {
        let bus = VirtualBus::new(VirtualBusConfig {
            epoch: Duration::from_secs(EPOCH_S),
            data_bitrate_bps: Some(5_000_000),
            ..VirtualBusConfig::default()
        });
        let mut tap = bus.tap();
        let mut check_tap = bus.tap();
        let node = bus.attach("sender");
        let mut recorder = Recorder::create(path, "vcan0").unwrap();
        let sender = tokio::spawn(async move {
            for frame in frames {
                node.send(frame).await.unwrap();
                tokio::time::sleep(Duration::from_millis(1)).await;
            }
        });
        drop(bus);
        let summary = record_tap(&mut tap, &mut recorder).await.unwrap();
        sender.await.unwrap();
        assert_eq!(summary.frames, count);
        assert_eq!(summary.missed, 0);
        assert_eq!(recorder.finish().unwrap(), count);
        let mut seen = Vec::new();
        while let Ok(frame) = check_tap.try_recv() {
            seen.push(frame);
        }
        seen
    })
}

fn run(command: &mut Command) -> String {
    let output = command
        .output()
        .unwrap_or_else(|error| panic!("cannot run {command:?}: {error}"));
    assert!(
        output.status.success(),
        "{command:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

#[test]
fn candump_log_converts_with_log2asc_and_back_with_asc2log() {
    if !require("candump_log_converts_with_log2asc", &[LOG2ASC, ASC2LOG]) {
        return;
    }
    let dir = scratch_dir("log2asc");
    let log = dir.join("capture.log");
    let asc = dir.join("capture.asc");
    let seen = record_virtual_run(&log);
    let written = std::fs::read_to_string(&log).unwrap();
    assert_eq!(written.lines().count(), 5);
    // Our own reader reads it back exactly.
    let entries = read_log(&log).unwrap();
    assert_eq!(
        entries
            .iter()
            .map(|e| (e.timestamp, e.frame))
            .collect::<Vec<_>>(),
        seen.iter()
            .map(|r| (r.timestamp, r.frame))
            .collect::<Vec<_>>()
    );

    run(Command::new("log2asc")
        .arg("-I")
        .arg(&log)
        .arg("-O")
        .arg(&asc)
        .arg("vcan0"));
    let asc_text = std::fs::read_to_string(&asc).unwrap();
    // ASC data lines: "<time> <channel> <id>[x] Rx d <dlc> <bytes...>"
    let asc_frames: Vec<String> = asc_text
        .lines()
        .filter(|line| line.contains(" Rx "))
        .map(|line| line.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect();
    // log2asc makes times relative to the first frame.
    let expected: Vec<String> = [
        "1 2A1 Rx d 8 00 11 22 33 44 55 66 77",
        "1 200FD01x Rx d 2 AB CD",
        "1 7 Rx d 0",
        "1 1FFFFFFFx Rx d 8 FF FF FF FF FF FF FF FF",
        "1 7FF Rx d 1 01",
    ]
    .iter()
    .zip(&seen)
    .map(|(rest, received)| {
        let offset = received.timestamp - seen[0].timestamp;
        format!("{}.{:06} {rest}", offset.as_secs(), offset.subsec_micros())
    })
    .collect();
    assert_eq!(asc_frames, expected);

    // And asc2log turns it back into a log our reader accepts, with the same frames and gaps.
    let back = parse_log(&run(Command::new("asc2log").arg("-I").arg(&asc))).unwrap();
    assert_eq!(
        back.iter().map(|e| e.frame).collect::<Vec<_>>(),
        sample_frames()
    );
    for (pair_back, pair_seen) in back.windows(2).zip(seen.windows(2)) {
        assert_eq!(
            pair_back[1].timestamp - pair_back[0].timestamp,
            pair_seen[1].timestamp - pair_seen[0].timestamp
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn candump_log_is_accepted_by_log2long() {
    if !require("candump_log_is_accepted_by_log2long", &[LOG2LONG]) {
        return;
    }
    let dir = scratch_dir("log2long");
    let log = dir.join("capture.log");
    record_virtual_run(&log);
    let long = run(Command::new("sh")
        .arg("-c")
        .arg(format!("log2long < '{}'", log.display())));
    let lines: Vec<&str> = long.lines().collect();
    assert_eq!(lines.len(), 5);
    assert!(lines[0].contains("vcan0") && lines[0].contains("2A1") && lines[0].contains("[8]"));
    assert!(lines[1].contains("0200FD01") && lines[1].contains("AB CD"));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn pcap_opens_in_tshark_with_the_right_ids_and_data() {
    if !require("pcap_opens_in_tshark", &[TSHARK]) {
        return;
    }
    let dir = scratch_dir("tshark");
    let pcap = dir.join("capture.pcap");
    let seen = record_virtual_run(&pcap);
    let bytes = std::fs::read(&pcap).unwrap();
    assert_eq!(parse_capture(&bytes).unwrap(), seen);

    let fields = run(Command::new("tshark")
        .arg("-r")
        .arg(&pcap)
        .args(["-T", "fields"])
        .args(["-e", "frame.time_epoch"])
        .args(["-e", "can.id", "-e", "can.flags.xtd", "-e", "can.len"])
        .args(["-e", "data.data"]));
    let rows: Vec<Vec<&str>> = fields
        .lines()
        .map(|line| line.split('\t').collect())
        .collect();
    assert_eq!(rows.len(), seen.len());
    for (row, received) in rows.iter().zip(&seen) {
        let frame = received.frame;
        let expected_time = format!(
            "{}.{:06}",
            received.timestamp.as_secs(),
            received.timestamp.subsec_micros()
        );
        assert!(
            row[0].starts_with(&expected_time),
            "{row:?} vs {expected_time}"
        );
        assert_eq!(row[1], frame.raw_id().to_string());
        assert_eq!(row[2], if frame.is_extended() { "1" } else { "0" });
        assert_eq!(row[3], frame.len().to_string());
        let hex: String = frame.data().iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(row.get(4).copied().unwrap_or(""), hex);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn pcapng_of_several_buses_names_each_frame_s_bus_in_tshark() {
    if !require("pcapng_of_several_buses", &[TSHARK]) {
        return;
    }
    let dir = scratch_dir("pcapng");
    let path = dir.join("buses.pcapng");
    let frames = sample_frames();
    let mut writer = bus::pcapng::PcapngWriter::new(Vec::new(), &["can0", "can3"]).unwrap();
    for (k, frame) in frames.iter().enumerate() {
        let received = ReceivedFrame {
            frame: *frame,
            timestamp: Duration::from_secs(EPOCH_S) + Duration::from_millis(k as u64),
        };
        writer.write((k % 2) as u32, &received).unwrap();
    }
    std::fs::write(&path, writer.finish().unwrap()).unwrap();
    let fields = run(Command::new("tshark")
        .arg("-r")
        .arg(&path)
        .args(["-T", "fields"])
        .args(["-e", "frame.interface_name", "-e", "can.id"]));
    let rows: Vec<&str> = fields.lines().collect();
    let expected: Vec<String> = frames
        .iter()
        .enumerate()
        // tshark prints can.id in decimal.
        .map(|(k, f)| format!("{}\t{}", ["can0", "can3"][k % 2], f.id().raw()))
        .collect();
    assert_eq!(rows, expected);
}

/// CAN FD lines (`ID##F…`) as can-utils reads them: log2asc writes a `CANFD` line with BRS,
/// ESI, DLC and length; asc2log turns it back into the same frames.
#[test]
fn fd_candump_log_converts_with_log2asc_and_back_with_asc2log() {
    if !require("fd_candump_log_converts_with_log2asc", &[LOG2ASC, ASC2LOG]) {
        return;
    }
    let dir = scratch_dir("fd-log2asc");
    let log = dir.join("capture.log");
    let asc = dir.join("capture.asc");
    let seen = record_frames(&log, fd_sample_frames());
    assert_eq!(
        seen.iter().map(|r| r.frame).collect::<Vec<_>>(),
        fd_sample_frames()
    );
    run(Command::new("log2asc")
        .arg("-I")
        .arg(&log)
        .arg("-O")
        .arg(&asc)
        .arg("vcan0"));
    let asc_text = std::fs::read_to_string(&asc).unwrap();
    let rows: Vec<Vec<&str>> = asc_text
        .lines()
        .filter(|line| line.contains(" Rx "))
        .map(|line| line.split_whitespace().collect())
        .collect();
    assert_eq!(rows.len(), seen.len(), "{asc_text}");
    for (row, received) in rows.iter().zip(&seen) {
        let frame = received.frame;
        let id = if frame.is_extended() {
            format!("{:X}x", frame.raw_id())
        } else {
            format!("{:X}", frame.raw_id())
        };
        let bytes: Vec<String> = frame.data().iter().map(|b| format!("{b:02X}")).collect();
        if frame.is_fd() {
            // "<time> CANFD <channel> Rx <id> <brs> <esi> <dlc hex> <len> <bytes…> …"
            assert_eq!(row[1], "CANFD", "{row:?}");
            assert_eq!(row[4], id, "{row:?}");
            assert_eq!(row[5], if frame.brs() { "1" } else { "0" }, "{row:?}");
            assert_eq!(row[6], if frame.esi() { "1" } else { "0" }, "{row:?}");
            assert_eq!(row[7], format!("{:x}", frame.dlc()), "{row:?}");
            assert_eq!(row[8], frame.len().to_string(), "{row:?}");
            assert_eq!(&row[9..9 + frame.len()], &bytes[..], "{row:?}");
        } else {
            // "<time> <channel> <id> Rx d <dlc> <bytes…>"
            assert_eq!(&row[2..6], &[&id[..], "Rx", "d", &frame.len().to_string()]);
            assert_eq!(&row[6..], &bytes[..], "{row:?}");
        }
    }
    let back = parse_log(&run(Command::new("asc2log").arg("-I").arg(&asc))).unwrap();
    assert_eq!(
        back.iter().map(|e| e.frame).collect::<Vec<_>>(),
        fd_sample_frames()
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A pcap of classic and CAN FD frames as tshark dissects it: the identifier, the length and
/// the payload of each, and for the CAN FD ones their BRS and ESI flags.
#[test]
fn fd_pcap_opens_in_tshark_with_flags_and_lengths() {
    if !require("fd_pcap_opens_in_tshark", &[TSHARK]) {
        return;
    }
    let dir = scratch_dir("fd-tshark");
    let pcap = dir.join("capture.pcap");
    let seen = record_frames(&pcap, fd_sample_frames());
    let bytes = std::fs::read(&pcap).unwrap();
    // CAN FD frames end between microseconds; pcap keeps microseconds.
    let to_micros = |r: &ReceivedFrame| (r.frame, r.timestamp.as_micros());
    assert_eq!(
        parse_capture(&bytes)
            .unwrap()
            .iter()
            .map(to_micros)
            .collect::<Vec<_>>(),
        seen.iter().map(to_micros).collect::<Vec<_>>()
    );
    let fields = run(Command::new("tshark")
        .arg("-r")
        .arg(&pcap)
        .args(["-T", "fields"])
        .args(["-e", "_ws.col.Protocol", "-e", "can.id", "-e", "can.len"])
        .args(["-e", "canfd.flags.brs", "-e", "canfd.flags.esi"])
        .args(["-e", "data.data"]));
    let rows: Vec<Vec<&str>> = fields
        .lines()
        .map(|line| line.split('\t').collect())
        .collect();
    assert_eq!(rows.len(), seen.len(), "{fields}");
    for (row, received) in rows.iter().zip(&seen) {
        let frame = received.frame;
        let hex: String = frame.data().iter().map(|b| format!("{b:02x}")).collect();
        // tshark prints booleans as 1/0 and the identifier in decimal; a classic frame has
        // no CAN FD flags.
        let flag = |on: bool| if on { "1" } else { "0" }.to_owned();
        let (protocol, brs, esi) = if frame.is_fd() {
            ("CANFD", flag(frame.brs()), flag(frame.esi()))
        } else {
            ("CAN", String::new(), String::new())
        };
        let expected = [
            protocol.to_owned(),
            frame.raw_id().to_string(),
            frame.len().to_string(),
            brs,
            esi,
            hex,
        ];
        assert_eq!(row, &expected, "{fields}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}
