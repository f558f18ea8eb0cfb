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

/// Runs `scenario` with its outputs under `out`, then decodes the capture it wrote there
/// (`capture`, relative to `out`) by that scenario's devices: the decoded text.
fn run_then_decode_by_scenario(scenario: &Path, out: &Path, capture: &str) -> String {
    armhil_ok(&[
        "run".as_ref(),
        scenario.as_ref(),
        "--out".as_ref(),
        out.as_ref(),
    ]);
    armhil_ok(&[
        "decode".as_ref(),
        out.join(capture).as_ref(),
        "--scenario".as_ref(),
        scenario.as_ref(),
    ])
}

#[test]
fn a_robot_s_capture_is_decoded_by_its_scenario_s_devices_with_each_frame_s_bus() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenario = root.join("scenarios/robot/arm6_hold_gravity.yaml");
    let out = tempfile::tempdir().expect("a temporary folder");
    let capture = out.path().join("arm6_hold_gravity/bus.pcapng");
    let text = run_then_decode_by_scenario(&scenario, out.path(), "arm6_hold_gravity/bus.pcapng");
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
    let text = run_then_decode_by_scenario(&scenario, &dir.path().join("out"), "hold/bus.log");
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

/// The Damiao decoder (`armhil::devices::damiao::decode_damiao`, written apart from both Damiao
/// codecs) against every shared vector of `fixtures/damiao/`: each frame is named by its
/// `cmd` and its fields carry the annotated values (MIT and feedback within the quantisation
/// step, the rest exactly as printed).
#[test]
fn every_damiao_vector_decodes_to_its_annotated_fields() {
    use armhil::devices::damiao::{decode_damiao, DamiaoWireMotor};
    use driver::damiao::Model;

    let dir = testkit::fixtures::repo_path("damiao");
    let vectors = testkit::fixtures::read_dir(&dir).expect("fixtures/damiao reads");
    let text = |v: &testkit::fixtures::Vector, key: &str| -> String {
        v.text(key)
            .unwrap_or_else(|e| panic!("{}: {e}", v.name))
            .to_owned()
    };
    let int = |v: &testkit::fixtures::Vector, key: &str| v.int(key).expect(key);
    let real = |v: &testkit::fixtures::Vector, key: &str| v.float(key).expect(key);
    let mut count = 0;
    for v in &vectors {
        let model = Model::parse(&text(v, "model")).expect("a model the driver knows");
        let motor = DamiaoWireMotor {
            esc_id: int(v, "esc_id") as u16,
            mst_id: int(v, "mst_id") as u16,
            model,
        };
        let decoded = decode_damiao(&v.frame, &[motor])
            .unwrap_or_else(|e| panic!("{}: {e}", v.name))
            .unwrap_or_else(|| panic!("{}: not decoded", v.name));
        let field = |name: &str| -> String {
            decoded
                .fields
                .iter()
                .find(|f| f.name == name)
                .unwrap_or_else(|| panic!("{}: no field {name} in {decoded:?}", v.name))
                .value
                .clone()
        };
        let number = |name: &str| -> f64 { field(name).parse().expect("a number") };
        assert_eq!(number("motor"), int(v, "esc_id") as f64, "{}", v.name);
        let ranges = model.ranges(driver::damiao::RangeTable::Current);
        let (pmax, vmax, tmax) = (
            f64::from(ranges.pmax),
            f64::from(ranges.vmax),
            f64::from(ranges.tmax),
        );
        // A packed field: its code (`raw`) and its value clamped into the range, within
        // one step (the codes truncate) and the four printed decimals.
        let packed = |name: &str, key: &str, raw: &str, (lo, hi): (f64, f64), bits: u32| {
            let step = (hi - lo) / f64::from((1u32 << bits) - 1);
            let got = number(name);
            let from_raw = int(v, raw) as f64 * step + lo;
            assert!(
                (got - from_raw).abs() <= 5e-5,
                "{}: {name} {got} vs code {from_raw}",
                v.name
            );
            let want = real(v, key).clamp(lo, hi);
            assert!(
                (got - want).abs() <= step + 5e-5,
                "{}: {name} {got} vs {want}",
                v.name
            );
        };
        let cmd = text(v, "cmd");
        let expected_name = match cmd.as_str() {
            "reg_read" => "register_read",
            "reg_write" => "register_write",
            "reg_save" => "register_save",
            "reg_reply" if int(v, "op") == 0x33 => "register_read_reply",
            "reg_reply" => "register_write_reply",
            other => other,
        };
        assert_eq!(decoded.name, expected_name, "{}", v.name);
        match cmd.as_str() {
            "enable" | "disable" | "set_zero" | "clear_error" | "reg_save" | "refresh" => {}
            "mit" => {
                packed("p", "p_des_rad", "p_raw", (-pmax, pmax), 16);
                packed("v", "v_des_rad_s", "v_raw", (-vmax, vmax), 12);
                packed("kp", "kp", "kp_raw", (0.0, 500.0), 12);
                packed("kd", "kd", "kd_raw", (0.0, 5.0), 12);
                packed("t", "t_ff_nm", "t_raw", (-tmax, tmax), 12);
            }
            "pos_vel" => {
                assert_eq!(number("p"), real(v, "p_des_rad"), "{}", v.name);
                assert_eq!(number("v"), real(v, "v_des_rad_s"), "{}", v.name);
            }
            "velocity" => assert_eq!(number("v"), real(v, "v_des_rad_s"), "{}", v.name),
            "force_pos" => {
                assert_eq!(number("p"), real(v, "p_des_rad"), "{}", v.name);
                assert_eq!(number("v"), int(v, "v_raw") as f64 / 100.0, "{}", v.name);
                assert_eq!(number("i"), int(v, "i_raw") as f64 / 10_000.0, "{}", v.name);
                assert_eq!(number("v"), real(v, "v_des_rad_s").min(100.0), "{}", v.name);
                assert_eq!(number("i"), real(v, "i_des").min(1.0), "{}", v.name);
            }
            "reg_read" => assert_eq!(field("reg"), text(v, "reg"), "{}", v.name),
            "reg_write" | "reg_reply" => {
                assert_eq!(field("reg"), text(v, "reg"), "{}", v.name);
                // f32 registers print as the f32 reads (`0.945`), u32 ones whole.
                assert_eq!(
                    number("value") as f32,
                    real(v, "value") as f32,
                    "{}",
                    v.name
                );
            }
            "feedback" => {
                let tol = real(v, "tol");
                assert_eq!(field("state"), text(v, "state_name"), "{}", v.name);
                for (name, key) in [("p", "pos_rad"), ("v", "vel_rad_s"), ("t", "torque_nm")] {
                    let (got, want) = (number(name), real(v, key));
                    assert!(
                        (got - want).abs() <= tol,
                        "{}: {name} {got} vs {want}",
                        v.name
                    );
                }
                assert_eq!(number("mos"), real(v, "t_mos_c"), "{}", v.name);
                assert_eq!(number("rotor"), real(v, "t_rotor_c"), "{}", v.name);
            }
            other => panic!("{}: no check for cmd={other}", v.name),
        }
        count += 1;
    }
    assert_eq!(count, 66, "every vector of fixtures/damiao/");
}

/// `armhil decode --device damiao` on the command vectors of three OpenArm-like motors: each
/// frame named with its values in units, by its own motor's model.
#[test]
fn decode_device_damiao_names_each_command_with_its_motor_s_ranges() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let log = root.join("fixtures/damiao/commands.log");
    let out = armhil_ok(&[
        "decode".as_ref(),
        log.as_ref(),
        "--device".as_ref(),
        "damiao".as_ref(),
        "--motor".as_ref(),
        "1:DM4310".as_ref(),
        "--motor".as_ref(),
        "2:DM8009".as_ref(),
        "--motor".as_ref(),
        "0x03:DM4340:0x13".as_ref(),
    ]);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 21, "{out}");
    assert_eq!(lines[0], "0.000000  001  enable  motor=1");
    assert_eq!(
        lines[5],
        "0.005000  001  mit  motor=1  p=0.9997 rad  v=2.1905 rad/s  kp=49.9389  kd=1.1990  t=1.4969 N.m"
    );
    // The DM4340's VMAX is 10 rad/s (v 5.0 in the vector), the DM8009's TMAX 54 N·m (t -20).
    assert!(
        lines[11].contains("  mit  motor=3  p=0.4999 rad  v=4.9988 rad/s"),
        "{}",
        lines[11]
    );
    assert!(
        lines[12].contains("  mit  motor=2  ") && lines[12].contains("t=-20.0044 N.m"),
        "{}",
        lines[12]
    );
    assert_eq!(
        lines[13],
        "0.013000  101  pos_vel  motor=1  p=1.5000 rad  v=2.0000 rad/s"
    );
    assert_eq!(
        lines[15],
        "0.015000  201  velocity  motor=1  v=5.0000 rad/s"
    );
    assert_eq!(
        lines[18],
        "0.018000  301  force_pos  motor=1  p=1.0000 rad  v=5.00 rad/s  i=0.5000"
    );
    // Without --motor, the default motor (1:DM4310): motor 3's frame is nobody's.
    let default = armhil_ok(&[
        "decode".as_ref(),
        log.as_ref(),
        "--device".as_ref(),
        "damiao".as_ref(),
    ]);
    let default: Vec<&str> = default.lines().collect();
    assert_eq!(default[5], lines[5]);
    assert_eq!(default[11], "0.011000  003  ?  raw=851EBFF23D6B78DA");
}

/// A Damiao bench's capture decoded by its scenario: every frame is named by the `damiao`
/// device (commands, the host's reads, the motor's feedback with its DM4310 ranges), and
/// `--device damiao` with the motor given by `--motor` reads the same lines.
#[test]
fn a_damiao_bench_s_capture_is_decoded_by_its_scenario() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenario = root.join("scenarios/damiao/mit_hold.yaml");
    let out = tempfile::tempdir().expect("a temporary folder");
    let by_scenario = run_then_decode_by_scenario(&scenario, out.path(), "mit_hold/bus.log");
    let capture = out.path().join("mit_hold/bus.log");
    assert!(
        by_scenario.lines().all(|l| !l.contains("  ?  raw=")),
        "an undecoded frame:\n{by_scenario}"
    );
    assert!(
        by_scenario.contains("  001  enable  motor=1"),
        "{by_scenario}"
    );
    assert!(
        by_scenario.contains("  7FF  refresh  motor=1"),
        "{by_scenario}"
    );
    // The driver's codes truncate: kp 20 is sent as 163 of 4095 over 0..=500.
    assert!(
        by_scenario
            .contains("  001  mit  motor=1  p=0.9997 rad  v=-0.0073 rad/s  kp=19.9023  kd=1.0000"),
        "{by_scenario}"
    );
    // Holding against gravity: the feedback's torque is the 0.80 N·m the snapshot shows.
    assert!(
        by_scenario
            .lines()
            .any(|l| l.contains("feedback  motor=1  state=enabled  p=0.95") && l.contains("t=0.80")),
        "{by_scenario}"
    );
    let by_protocol = armhil_ok(&[
        "decode".as_ref(),
        capture.as_ref(),
        "--device".as_ref(),
        "damiao".as_ref(),
        "--motor".as_ref(),
        "1:DM4310".as_ref(),
    ]);
    assert_eq!(by_scenario, by_protocol);
}

/// The options are the protocols' to read: a flag a protocol cannot read, or a motor its model
/// table does not know, is an error naming the flag, and nothing is printed.
#[test]
fn decode_names_the_flag_a_protocol_refuses() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let log = root.join("fixtures/damiao/commands.log");
    let refused = |args: &[&str]| {
        let out = Command::new(ARMHIL)
            .arg("decode")
            .arg(&log)
            .args(args)
            .output()
            .expect("armhil runs");
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(out.stdout.is_empty(), "{args:?} printed frames");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let e = refused(&["--device", "damiao", "--model", "DM4310"]);
    assert!(
        e.contains("`--model` is not read by `--device damiao`: give each Damiao motor as --motor ESC_ID:MODEL[:MST_ID]"),
        "{e}"
    );
    let e = refused(&["--device", "damiao", "--motor", "1:DM431"]);
    assert!(
        e.contains("`--motor 1:DM431`: unknown Damiao model `DM431`")
            && e.contains("did you mean `DM4310`?"),
        "{e}"
    );
    let e = refused(&["--device", "robstride", "--motor", "1:DM4310"]);
    assert!(
        e.contains("`--motor 1:DM4310`: unknown RobStride model `DM4310`"),
        "{e}"
    );
    let e = refused(&["--device", "robstride", "--model", "DM4310"]);
    assert!(
        e.contains("a Damiao motor is given as --motor ID:MODEL with --device damiao"),
        "{e}"
    );
    let e = refused(&["--device", "robstride-mit", "--motor", "1:RS03"]);
    assert!(
        e.contains("`--motor` is not read by `--device robstride-mit`"),
        "{e}"
    );
    // A value that is no ID:MODEL at all is the command line's error.
    let e = refused(&["--device", "damiao", "--motor", "DM4310"]);
    assert!(
        e.contains("expected ID:MODEL or ID:MODEL:FEEDBACK_ID"),
        "{e}"
    );
    let e = refused(&[
        "--scenario",
        "scenarios/damiao/mit_hold.yaml",
        "--motor",
        "1:DM4310",
    ]);
    assert!(e.contains("cannot be used with"), "{e}");
}
