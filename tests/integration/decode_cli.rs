//! `armhil decode` on what `armhil run` records: a robot's two buses in one pcapng capture,
//! decoded by the scenario's own devices.

use std::path::Path;
use std::process::Command;

const ARMHIL: &str = env!("CARGO_BIN_EXE_armhil");

/// `armhil ARGS…`, which must succeed: its standard output.
fn armhil_ok(args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new(ARMHIL)
        .args(args)
        .output()
        .expect("armhil runs");
    assert!(
        out.status.success(),
        "armhil {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_robot_s_capture_is_decoded_by_its_scenario_s_devices_with_each_frame_s_bus() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenario = root.join("scenarios/robot/arm6_hold_gravity.yaml");
    let out = tempfile::tempdir().expect("a temporary folder");
    armhil_ok(&[
        "run".as_ref(),
        scenario.as_ref(),
        "--out".as_ref(),
        out.path().as_ref(),
    ]);
    let capture = out.path().join("arm6_hold_gravity/bus.pcapng");

    let text = armhil_ok(&[
        "decode".as_ref(),
        capture.as_ref(),
        "--scenario".as_ref(),
        scenario.as_ref(),
    ]);
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

/// CAN ids repeat across a robot's buses: here motors 1 to 3 are RS03/RS04 on can0 and RS02
/// on can1. Each command and reply is scaled by the model of the motor on the frame's own bus:
/// can1's motor 1 held at kp 100 reads kp 100 (by can0's RS03 ranges, as before decoding knew
/// buses, it read kp 1000).
#[test]
fn frames_of_motors_sharing_an_id_on_two_buses_decode_by_their_own_bus() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().expect("a temporary folder");
    let urdf = root.join("urdf/robstride_arm6.urdf");
    let robot = dir.path().join("arm.yaml");
    std::fs::write(
        &robot,
        format!(
            "robot: arm\nurdf: {}\nbase: fixed\nbuses:\n  - {{name: can0, bitrate: 1000000}}\n  - {{name: can1, bitrate: 1000000}}\nactuators:\n  - {{joint: shoulder_yaw, model: RS03, id: 1, bus: can0}}\n  - {{joint: shoulder_pitch, model: RS04, id: 2, bus: can0}}\n  - {{joint: elbow_pitch, model: RS03, id: 3, bus: can0}}\n  - {{joint: wrist_roll, model: RS02, id: 1, bus: can1}}\n  - {{joint: wrist_pitch, model: RS02, id: 2, bus: can1}}\n  - {{joint: flange_roll, model: RS02, id: 3, bus: can1}}\n",
            urdf.display()
        ),
    )
    .expect("robot file written");
    let scenario = dir.path().join("hold.yaml");
    std::fs::write(
        &scenario,
        "name: hold\nbench:\n  devices:\n    arm: {kind: actuator_group, robot: arm.yaml}\nsteps:\n  - group: {do: enable}\n  - group: {do: hold, targets_rad: {shoulder_yaw: 0, shoulder_pitch: 0, elbow_pitch: 0, wrist_roll: 0, wrist_pitch: 0, flange_roll: 0}, kp: 100, kd: 4}\n  - wait_ms: 20\n",
    )
    .expect("scenario written");
    let out = dir.path().join("out");
    armhil_ok(&[
        "run".as_ref(),
        scenario.as_ref(),
        "--out".as_ref(),
        out.as_ref(),
    ]);
    let text = armhil_ok(&[
        "decode".as_ref(),
        out.join("hold/bus.log").as_ref(),
        "--scenario".as_ref(),
        scenario.as_ref(),
    ]);
    let kp_of = |bus: &str| -> Vec<f64> {
        text.lines()
            .filter(|l| l.contains(&format!("  {bus}  ")) && l.contains("OpControl  motor=1"))
            .filter_map(|l| l.split("kp=").nth(1)?.split(' ').next()?.parse().ok())
            .collect()
    };
    let (can0, can1) = (kp_of("can0"), kp_of("can1"));
    assert!(
        !can0.is_empty() && !can1.is_empty(),
        "no hold command to motor 1 on each bus:\n{}",
        &text[..text.len().min(3000)]
    );
    for kp in can0.iter().chain(&can1) {
        assert!((kp - 100.0).abs() < 0.1, "kp {kp}:\n{text}");
    }
}

/// An interface name is the capture's to choose: one holding an escape sequence is printed
/// escaped, never sent to the terminal as it is.
#[test]
fn control_characters_in_a_capture_s_interface_names_are_printed_escaped() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let log = dir.path().join("evil.log");
    std::fs::write(
        &log,
        "(0.000000) can\u{1b}[2J0 2A1#0000000000000000\n(0.001000) vcan1 2A1#0000000000000000\n",
    )
    .expect("log written");
    let out = Command::new(ARMHIL)
        .arg("decode")
        .arg(&log)
        .output()
        .expect("armhil runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!text.contains('\u{1b}'), "{text:?}");
    assert!(text.contains("can\\u{1b}[2J0"), "{text}");
}

/// `--device` takes the protocols the registered device kinds own (`armhil decode --help`
/// lists each with its help line), decodes with `piper` when not given, and refuses another
/// name with the known ones and the nearest of them.
#[test]
fn device_accepts_each_registered_protocol_and_suggests_one_for_an_unknown_name() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let log = root.join("fixtures/robstride/mit.log");
    let decode = |device: Option<&str>| {
        let mut command = Command::new(ARMHIL);
        command.arg("decode").arg(&log);
        if let Some(device) = device {
            command.args(["--device", device]);
        }
        command.output().expect("armhil runs")
    };
    let help = Command::new(ARMHIL)
        .args(["decode", "--help"])
        .output()
        .expect("armhil runs");
    let help = String::from_utf8_lossy(&help.stdout);

    let names: Vec<&str> = armhil::devices::wire_decoders().map(|d| d.name).collect();
    assert!(
        names.contains(&"piper") && names.contains(&"robstride-mit"),
        "{names:?}"
    );
    for wire in armhil::devices::wire_decoders() {
        let out = decode(Some(wire.name));
        assert!(
            out.status.success(),
            "--device {}: {}",
            wire.name,
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(!out.stdout.is_empty(), "--device {}: no output", wire.name);
        assert!(
            help.contains(&format!("- {}:", wire.name)) && help.contains(wire.help),
            "--device {} not listed:\n{help}",
            wire.name
        );
    }
    // The name picks the protocol: the MIT capture's commands are named by the MIT decoder.
    let mit = String::from_utf8_lossy(&decode(Some("robstride-mit")).stdout).into_owned();
    assert!(mit.contains("  MitCommand  motor=127"), "{mit}");
    // Without --device, the Piper's protocol.
    assert_eq!(decode(None).stdout, decode(Some("piper")).stdout);

    let unknown = decode(Some("robstrid"));
    let stderr = String::from_utf8_lossy(&unknown.stderr);
    assert_eq!(unknown.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("invalid value 'robstrid'"), "{stderr}");
    assert!(
        stderr.contains(&format!("[possible values: {}]", names.join(", "))),
        "{stderr}"
    );
    assert!(
        stderr.contains("a similar value exists: 'robstride'"),
        "{stderr}"
    );
}
