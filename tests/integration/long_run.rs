//! Long runs stay bounded. Memory: ten simulated minutes of a Piper scenario with every
//! recording on (about 1.8 million frames) must not hold the frames in memory (peak resident
//! memory of the `armhil run` process is read from Linux's /proc). Disk: a recording past
//! `--max-recording-mib` keeps the run's beginning and end within the limit and says what it
//! left out, and the trace thins itself out instead of growing.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use super::support::ARMHIL;

/// Peak resident set the run may reach. Today's figure is about 20 MB; holding every frame
/// of ten minutes in memory (as recordings once did) would add over 100 MB.
const PEAK_RSS_LIMIT_KB: u64 = 64 * 1024;

/// `VmHWM` (peak resident set, kB) of a live process, if it is still there.
fn peak_rss_kb(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find_map(|line| line.strip_prefix("VmHWM:"))
        .and_then(|rest| rest.trim().trim_end_matches("kB").trim().parse().ok())
}

fn write_scenario(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("ten_minutes.yaml");
    std::fs::write(
        &path,
        "name: ten_minutes\n\
         bench:\n  devices:\n    arm: {kind: piper}\n\
         record: {candump: true, pcap: true, plot: true}\n\
         steps:\n\
         \x20 - enable: {}\n\
         \x20 - move_j: {joints_deg: [30, 40, -40, 10, 20, 30]}\n\
         \x20 - wait_ms: 600000\n",
    )
    .unwrap();
    path
}

#[cfg(target_os = "linux")]
#[test]
fn ten_simulated_minutes_with_recordings_keep_memory_flat() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_scenario(dir.path());
    let out = dir.path().join("out");
    // A limit above the ten minutes' ~80 MB, so that every frame is written.
    let mut child = Command::new(ARMHIL)
        .args(["run", "--max-recording-mib", "1024", "--out"])
        .arg(&out)
        .arg(&file)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut peak_kb = 0;
    let status = loop {
        if let Some(kb) = peak_rss_kb(child.id()) {
            peak_kb = peak_kb.max(kb);
        }
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "the run failed: {status}");
    let log = out.join("ten_minutes/bus.log");
    let frames = std::fs::read_to_string(&log).unwrap().lines().count();
    println!("10 simulated minutes: {frames} frames recorded, peak RSS {peak_kb} kB");
    // The Piper's feedback is ~3,000 frames/s; a short recording would make the check
    // meaningless.
    assert!(
        frames > 1_500_000,
        "only {frames} frames in {}",
        log.display()
    );
    assert!(
        peak_kb > 0 && peak_kb < PEAK_RSS_LIMIT_KB,
        "peak RSS {peak_kb} kB (limit {PEAK_RSS_LIMIT_KB} kB)"
    );
}

/// The number after `key: ` on the first line at or after line `from` that starts with
/// `key` once indented (whole part only).
fn number_after(text: &str, key: &str, from: usize) -> u64 {
    text.lines()
        .skip(from)
        .find_map(|line| {
            let value = line.trim_start().strip_prefix(key)?.strip_prefix(": ")?;
            Some(value.trim().parse::<f64>().ok()? as u64)
        })
        .unwrap_or_else(|| panic!("no `{key}` in\n{text}"))
}

#[test]
fn a_long_run_keeps_its_recordings_within_their_limit() {
    const LIMIT_MIB: u64 = 4;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("two_minutes.yaml");
    std::fs::write(
        &file,
        "name: two_minutes\n\
         bench:\n  devices:\n    arm: {kind: piper}\n\
         record: {sample_period_ms: 5, candump: true, pcap: true}\n\
         steps:\n\
         \x20 - enable: {}\n\
         \x20 - wait_ms: 120000\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let output = Command::new(ARMHIL)
        .args([
            "run",
            "--max-recording-mib",
            &LIMIT_MIB.to_string(),
            "--out",
        ])
        .arg(&out)
        .arg(&file)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}");
    assert!(
        stdout.contains("note: the recording reached its limit of 4 MiB per file"),
        "{stdout}"
    );

    let dir = out.join("two_minutes");
    let limit = LIMIT_MIB << 20;
    for name in ["bus.log", "bus.pcap"] {
        let size = std::fs::metadata(dir.join(name)).unwrap().len();
        // A segment closes after the frame that fills it: three segments, a frame each over.
        assert!(size <= limit + 3 * 64, "{name}: {size} bytes");
        assert!(size >= limit / 2, "{name}: {size} bytes, too little kept");
    }
    let log = bus::candump::read_log(dir.join("bus.log")).unwrap();
    let pcap = bus::pcap::parse_capture(&std::fs::read(dir.join("bus.pcap")).unwrap()).unwrap();
    assert_eq!(log.len(), pcap.len());

    let result = std::fs::read_to_string(dir.join("result.yaml")).unwrap();
    let line_of = |wanted: &str| {
        result
            .lines()
            .position(|l| l.trim() == wanted)
            .unwrap_or_else(|| panic!("no `{wanted}` in\n{result}"))
    };
    let total = number_after(&result, "frames", line_of("bus:"));
    let omitted_line = line_of("recording_omitted:");
    let omitted = number_after(&result, "frames", omitted_line);
    let from_ms = number_after(&result, "from_ms", omitted_line);
    let to_ms = number_after(&result, "to_ms", omitted_line);
    assert_eq!(log.len() as u64 + omitted, total, "kept + omitted = seen");
    assert!(total > 300_000, "{total} frames in two minutes");
    // The kept frames surround the gap, and the file ends at the run's end.
    let gap = log
        .windows(2)
        .position(|w| w[1].timestamp - w[0].timestamp > Duration::from_millis(100))
        .expect("the recording has its gap");
    assert!(log[gap].timestamp.as_millis() <= u128::from(from_ms));
    assert!(log[gap + 1].timestamp.as_millis() >= u128::from(to_ms));
    assert!(log.last().unwrap().timestamp > Duration::from_secs(119));

    // 120 s at 5 ms is 24,000 samples: past 20,000 rows the trace halves to 10 ms.
    let period_ms = number_after(&result, "period_ms", 0);
    assert_eq!(period_ms, 10, "{result}");
    println!("two simulated minutes: {total} frames, {} kept", log.len());
}
