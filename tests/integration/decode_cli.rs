//! `armhil decode` on what `armhil run` records: a robot's two buses in one pcapng capture,
//! decoded by the scenario's own devices.

use std::path::Path;
use std::process::Command;

const ARMHIL: &str = env!("CARGO_BIN_EXE_armhil");

#[test]
fn a_robot_s_capture_is_decoded_by_its_scenario_s_devices_with_each_frame_s_bus() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenario = root.join("scenarios/robot/arm6_hold_gravity.yaml");
    let out = tempfile::tempdir().expect("a temporary folder");
    let run = Command::new(ARMHIL)
        .arg("run")
        .arg(&scenario)
        .arg("--out")
        .arg(out.path())
        .output()
        .expect("armhil runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let capture = out.path().join("arm6_hold_gravity/bus.pcapng");

    let decode = Command::new(ARMHIL)
        .arg("decode")
        .arg(&capture)
        .arg("--scenario")
        .arg(&scenario)
        .output()
        .expect("armhil runs");
    assert!(
        decode.status.success(),
        "{}",
        String::from_utf8_lossy(&decode.stderr)
    );
    let text = String::from_utf8_lossy(&decode.stdout);
    // Motor 6 (flange roll) sits on can1 and its status replies are named with its RS02 units;
    // motor 2 (shoulder pitch, RS04) on can0.
    let status_of = |bus: &str, motor: &str| {
        text.lines().any(|l| {
            let cols: Vec<&str> = l.split("  ").collect();
            cols.get(1) == Some(&bus)
                && cols.get(3) == Some(&"Status")
                && cols.get(4) == Some(&motor)
        })
    };
    assert!(
        status_of("can1", "motor=6"),
        "no status of motor 6 on can1:\n{}",
        &text[..text.len().min(2000)]
    );
    assert!(status_of("can0", "motor=2"), "no status of motor 2 on can0");
    assert!(!status_of("can0", "motor=6"), "motor 6 seen on can0");
    // The shoulder holds the arm against gravity: its torque is far from zero.
    let shoulder = text
        .lines()
        .rev()
        .find(|l| l.contains("Status  motor=2"))
        .expect("a shoulder status");
    let torque: f64 = shoulder
        .split("torque=")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .expect("a torque field");
    assert!(torque.abs() > 5.0, "{shoulder}");

    // bus.log (candump -L) holds the same frames with their interface: the same lines.
    let from_log = Command::new(ARMHIL)
        .arg("decode")
        .arg(out.path().join("arm6_hold_gravity/bus.log"))
        .arg("--scenario")
        .arg(&scenario)
        .output()
        .expect("armhil runs");
    let log_text = String::from_utf8_lossy(&from_log.stdout);
    let fields = |line: &str| line.split_once("  ").map(|(_, rest)| rest.to_owned());
    let pcap_lines: Vec<_> = text.lines().filter_map(fields).collect();
    let log_lines: Vec<_> = log_text.lines().filter_map(fields).collect();
    assert_eq!(pcap_lines.len(), log_lines.len());
    assert_eq!(pcap_lines[..50], log_lines[..50]);

    // `--device` and `--scenario` are two ways to choose; both at once is refused.
    let both = Command::new(ARMHIL)
        .arg("decode")
        .arg(&capture)
        .args(["--device", "piper", "--scenario"])
        .arg(&scenario)
        .output()
        .expect("armhil runs");
    assert_eq!(both.status.code(), Some(2));
}

/// A capture is read whole, so what is not a regular file is refused before reading: a FIFO
/// would block, `/dev/zero` never ends.
#[test]
fn a_capture_that_is_not_a_file_is_refused_by_name() {
    for path in ["/dev/zero", "/dev/zero.pcap"] {
        let out = Command::new(ARMHIL)
            .args(["decode", path])
            .output()
            .expect("armhil runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(stderr.contains(path), "{stderr}");
        assert_ne!(out.status.code(), Some(101), "a panic: {stderr}");
    }
}
