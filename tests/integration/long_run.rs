//! Memory stays flat over a long run: ten simulated minutes of a Piper scenario with every
//! recording on (about 1.8 million frames) must not hold the frames in memory. Peak resident
//! memory of the `armhil run` process is read from Linux's /proc.

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
    let mut child = Command::new(ARMHIL)
        .args(["run", "--out"])
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
