//! Broken scenarios: their errors must name the file, line and column.

use std::path::Path;

use armhil::harness::parse_scenario;

/// Parse `text` as `broken.yaml` and return the error's headline.
fn error_of(text: &str) -> String {
    match parse_scenario(Path::new("broken.yaml"), text) {
        Ok(_) => panic!("scenario unexpectedly valid:\n{text}"),
        Err(e) => e.scenario_error().expect("a scenario error").headline(),
    }
}

const BENCH: &str = "bench:\n  devices:\n    arm: {kind: piper}\n";

#[test]
fn typo_in_a_key_names_the_key_and_the_valid_ones() {
    let text =
        format!("{BENCH}steps:\n  - move_j: {{joints_deg: [0, 0, 0, 0, 0, 0], sped_pct: 20}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:46: unknown key `sped_pct`, expected one of device, id, timeout_ms, expect_error, joints_deg, speed_pct, every_ms; did you mean `speed_pct`?"
    );
}

#[test]
fn typo_in_a_top_level_key_is_an_error() {
    let text = format!("{BENCH}step:\n  - estop\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:4:1: unknown key `step`, expected one of name, description, tags, matrix, bench, record, faults, steps; did you mean `steps`?"
    );
}

#[test]
fn unknown_action_lists_the_actions() {
    let text = format!("{BENCH}steps:\n  - move_z: {{joints_deg: [0, 0, 0, 0, 0, 0]}}\n");
    let e = error_of(&text);
    assert!(
        e.starts_with(
            "broken.yaml:5:5: unknown step `move_z`; expected one of: wait_ms, inject, clear_faults, expect, wait_until, enable, disable"
        ),
        "{e}"
    );
}

#[test]
fn wrong_type_says_what_was_expected() {
    let text = format!("{BENCH}steps:\n  - wait_ms: soon\n");
    assert_eq!(error_of(&text), "broken.yaml:5:14: expected a whole number");
    let text = format!("{BENCH}steps:\n  - move_j: {{joints_deg: 90}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:26: expected a list ([a, b, ...])"
    );
}

#[test]
fn unknown_device_names_the_bench_devices() {
    let text = format!("{BENCH}steps:\n  - estop: {{device: left_arm}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:21: unknown device `left_arm`; the bench has: arm"
    );
}

#[test]
fn negative_timeout_is_rejected() {
    let text = format!("{BENCH}steps:\n  - wait_until: {{enabled: true, timeout_ms: -50}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:45: `timeout_ms` must be >= 0 (milliseconds), got -50"
    );
}

#[test]
fn out_of_range_joint_index_is_rejected() {
    let text = format!("{BENCH}steps:\n  - inject: {{fault: {{comm_loss: {{joint: 7}}}}}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:41: `joint`: joint index 7 out of range, expected 1..=6"
    );
}

#[test]
fn wrong_number_of_joints_is_rejected() {
    let text = format!("{BENCH}steps:\n  - move_j: {{joints_deg: [1, 2, 3]}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:26: `joints_deg` needs exactly 6 numbers, got 3"
    );
}

#[test]
fn fault_schedule_must_refer_to_a_known_step() {
    let text = format!("{BENCH}faults:\n  - {{after: mvoe, fault: estop}}\nsteps:\n  - move_j: {{joints_deg: [0, 0, 0, 0, 0, 0], id: move}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:13: `after`: no step has id `mvoe` (step ids: move)"
    );
}

#[test]
fn unknown_firmware_lists_the_emulated_ones() {
    let text =
        "bench:\n  devices:\n    arm: {kind: piper, firmware: S-V9.9-9}\nsteps:\n  - estop\n";
    let e = error_of(text);
    assert!(e.starts_with("broken.yaml:3:34: `firmware`: unknown Piper firmware `S-V9.9-9`; the emulator implements: S-V1.5-8"), "{e}");
}

#[test]
fn vcan_tag_refuses_in_process_features() {
    let text = format!("tags: [vcan]\n{BENCH}steps:\n  - inject: {{fault: estop}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:1:8: tagged `vcan` but needs the in-process emulator: inject `estop` (line 6)"
    );
}

#[test]
fn error_display_shows_the_source_line_with_a_caret() {
    let text = format!("{BENCH}steps:\n  - estop: {{device: left_arm}}\n");
    let e = parse_scenario(Path::new("broken.yaml"), &text).expect_err("invalid");
    let shown = e.to_string();
    assert!(
        shown.contains("5 |   - estop: {device: left_arm}\n  |                     ^"),
        "{shown}"
    );
}

#[test]
fn unknown_piper_fault_names_the_emulator_faults_and_suggests_one() {
    let text = format!("{BENCH}steps:\n  - inject: {{fault: {{comm_los: {{joint: 3}}}}}}\n");
    let err = error_of(&text);
    assert!(err.starts_with("broken.yaml:5:"), "{err}");
    assert!(err.contains("unknown fault `comm_los`"), "{err}");
    for kind in sim::piper::FaultKind::ALL {
        assert!(
            err.contains(kind.name()),
            "{} missing from: {err}",
            kind.name()
        );
    }
    assert!(err.ends_with("did you mean `comm_loss`?"), "{err}");
}

#[test]
fn piper_fault_with_a_required_joint_cannot_be_written_bare() {
    let text = format!("{BENCH}faults:\n  - {{at_ms: 100, fault: stall}}\nsteps:\n  - estop\n");
    let err = error_of(&text);
    assert!(err.starts_with("broken.yaml:5:"), "{err}");
    assert!(
        err.contains("`stall` needs arguments: write `stall: { ... }`"),
        "{err}"
    );
}

#[test]
fn durations_longer_than_an_hour_are_refused_at_check_time() {
    let text = format!("{BENCH}steps:\n  - wait_ms: 1000000000000\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:14: `wait_ms` must be at most 3600000 (one hour, in milliseconds), got 1000000000000"
    );
    let text = format!(
        "{BENCH}steps:\n  - move_j: {{joints_deg: [0, 0, 0, 0, 0, 0], timeout_ms: 3600001}}\n"
    );
    let e = error_of(&text);
    assert!(
        e.starts_with("broken.yaml:5:58: `timeout_ms` must be at most 3600000"),
        "{e}"
    );
    // One hour itself is fine.
    let text = format!("{BENCH}steps:\n  - wait_ms: 3600000\n");
    assert!(parse_scenario(Path::new("ok.yaml"), &text).is_ok());
}

#[test]
fn an_overlong_name_is_refused_at_check_time() {
    let text = format!("name: {}\n{BENCH}steps:\n  - wait_ms: 1\n", "a".repeat(300));
    let e = error_of(&text);
    assert!(
        e.starts_with("broken.yaml:1:7: `name` must be 1 to 100 characters"),
        "{e}"
    );
    let text = format!("name: {}\n{BENCH}steps:\n  - wait_ms: 1\n", "a".repeat(100));
    assert!(parse_scenario(Path::new("ok.yaml"), &text).is_ok());
}

/// Load `bytes` as a file and return the error's headline with the temporary folder cut off.
fn load_error_of(bytes: &[u8]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.yaml");
    std::fs::write(&path, bytes).unwrap();
    match armhil::harness::load_scenario(&path) {
        Ok(_) => panic!("scenario unexpectedly valid"),
        Err(e) => e
            .scenario_error()
            .expect("a scenario error with a position")
            .headline()
            .replace(&format!("{}/", dir.path().display()), ""),
    }
}

#[test]
fn invalid_utf8_is_reported_at_its_line_and_column() {
    let mut bytes = format!("{BENCH}steps:\n  - wait_ms: 1 # caf").into_bytes();
    let offset = bytes.len();
    bytes.extend_from_slice(&[0xE9, b'\n']);
    assert_eq!(
        load_error_of(&bytes),
        format!("bad.yaml:5:21: not valid UTF-8 (byte offset {offset}); save the file as UTF-8")
    );
}

#[test]
fn utf16_is_recognised() {
    let mut bytes = vec![0xFF, 0xFE];
    for unit in format!("{BENCH}steps:\n  - wait_ms: 1\n").encode_utf16() {
        bytes.extend_from_slice(&unit.to_le_bytes());
    }
    assert_eq!(
        load_error_of(&bytes),
        "bad.yaml:1:1: the file is UTF-16; save it as UTF-8"
    );
}

#[test]
fn yaml_limits_are_reported_in_plain_words() {
    let aliases = format!(
        "name: &a x\ntags: [{}]\n{BENCH}steps:\n  - wait_ms: 1\n",
        "*a, ".repeat(50_001)
    );
    let e = error_of(&aliases);
    assert!(
        e.contains("the file exceeds the YAML reader's limit on aliases (reached 50001)"),
        "{e}"
    );
    assert!(!e.contains('{') && !e.contains("budget"), "{e}");
}

#[test]
fn a_huge_bad_token_is_not_echoed_whole() {
    let token = "x".repeat(10_000_000);
    let text = format!("{BENCH}steps:\n  - {token}: 1\n");
    let error = match parse_scenario(Path::new("broken.yaml"), &text) {
        Ok(_) => panic!("valid"),
        Err(e) => e.to_string(),
    };
    assert!(error.len() < 1000, "{} bytes of error", error.len());
    assert!(
        error.starts_with(&format!(
            "broken.yaml:5:5: unknown step `{}…",
            "x".repeat(39)
        )),
        "{}",
        &error[..200.min(error.len())]
    );
}

#[test]
fn physically_absurd_piper_fault_values_are_refused_at_their_position() {
    let text = format!(
        "{BENCH}steps:\n  - inject: {{fault: {{external_torque: {{joint: 1, torque_nm: 1e308}}}}}}\n"
    );
    let err = error_of(&text);
    assert!(err.starts_with("broken.yaml:5:"), "{err}");
    assert!(
        err.ends_with("`torque_nm` must be between -320 and 320, got 1e308"),
        "{err}"
    );
    let text = format!(
        "{BENCH}faults:\n  - {{at_ms: 10, fault: {{motor_over_temp: {{joint: 2, temp_c: 1e308}}}}}}\nsteps:\n  - wait_ms: 20\n"
    );
    let err = error_of(&text);
    assert!(err.starts_with("broken.yaml:5:"), "{err}");
    assert!(
        err.ends_with("`temp_c` must be between -40 and 200, got 1e308"),
        "{err}"
    );
    let text =
        format!("{BENCH}steps:\n  - inject: {{fault: {{under_voltage: {{voltage_v: -1}}}}}}\n");
    assert!(error_of(&text).ends_with("`voltage_v` must be between 0 and 60, got -1"));
    // A 300-digit number is not echoed whole.
    let digits = format!("1{}", "0".repeat(300));
    let text = format!(
        "{BENCH}steps:\n  - inject: {{fault: {{external_torque: {{joint: 1, torque_nm: {digits}}}}}}}\n"
    );
    let err = error_of(&text);
    assert!(err.len() < 200, "{err}");
    // Plausible values are accepted.
    let text = format!(
        "{BENCH}steps:\n  - inject: {{fault: {{external_torque: {{joint: 1, torque_nm: -15}}}}}}\n"
    );
    assert!(parse_scenario(Path::new("ok.yaml"), &text).is_ok());
}

#[test]
fn physically_absurd_robstride_values_are_refused_at_their_position() {
    let bench = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS00}]}\n";
    for (args, message) in [
        (
            "do: external_torque, torque_nm: 1e308",
            "`torque_nm` must be between -1200 and 1200, got 1e308",
        ),
        (
            "do: set_temperature, temp_c: 1e308",
            "`temp_c` must be between -40 and 200, got 1e308",
        ),
    ] {
        let text = format!("{bench}steps:\n  - robstride: {{motor: 1, {args}}}\n");
        let err = error_of(&text);
        assert!(err.starts_with("broken.yaml:5:"), "{err}");
        assert!(err.ends_with(message), "{err}");
    }
}

#[test]
fn typo_in_an_inject_key_lists_its_keys_with_the_alias() {
    let text = format!("{BENCH}steps:\n  - inject: {{fault: estop, durration_ms: 5}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:28: unknown key `durration_ms`, expected one of id, device, duration_ms, for_ms, bus, fault; did you mean `duration_ms`?"
    );
}

#[test]
fn an_inject_without_its_fault_names_the_missing_key() {
    let text = format!("{BENCH}steps:\n  - inject: {{for_ms: 5}}\n");
    assert!(
        error_of(&text).contains("missing field `fault`"),
        "{}",
        error_of(&text)
    );
}

/// `under_voltage` is a fault of two kinds with different arguments: the bench decides whose.
#[test]
fn a_key_two_kinds_share_is_read_as_the_bench_kind_s() {
    let robstride = "bench:\n  devices:\n    motor: {kind: robstride}\nsteps:\n  - inject: {fault: {under_voltage: {voltage_v: -1}}}\n";
    let piper =
        format!("{BENCH}steps:\n  - inject: {{fault: {{under_voltage: {{voltage_v: -1}}}}}}\n");
    let (robstride, piper) = (error_of(robstride), error_of(&piper));
    assert_ne!(robstride, piper, "both benches read the key alike");
    // A step of a kind not on the bench is unknown, and the list holds this bench's steps.
    let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: enable}}\n");
    let e = error_of(&text);
    assert!(e.contains("unknown step `robstride`"), "{e}");
    assert!(
        !e.contains(
            "expected one of: wait_ms, inject, clear_faults, expect, wait_until, robstride"
        ),
        "{e}"
    );
}
