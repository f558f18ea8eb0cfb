//! Rig files: entries become command lines, and each mistake is named at its place.

use std::path::PathBuf;

use super::*;

/// Kinds as the CLI registers them (this module knows none by name).
const PIPER: SimKind = SimKind {
    name: "piper",
    positional_keys: &[],
    output_keys: &["state_file", "record"],
};
const REALMAN: SimKind = SimKind {
    name: "realman",
    positional_keys: &[],
    output_keys: &["state_file"],
};
const ROBSTRIDE: SimKind = SimKind {
    name: "robstride",
    positional_keys: &[],
    output_keys: &["state_file"],
};
const ROBOT: SimKind = SimKind {
    name: "robot",
    positional_keys: &["file"],
    output_keys: &["state_file"],
};
const KINDS: [SimKind; 4] = [PIPER, REALMAN, ROBSTRIDE, ROBOT];

fn write(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rig.yaml");
    std::fs::write(&file, text).unwrap();
    (dir, file)
}

fn load(text: &str) -> Result<RigFile, String> {
    let (_dir, file) = write(text);
    load_rig_file(&file, &KINDS).map_err(|e| match e {
        RigFileError::Invalid(e) => e.headline().rsplit_once(".yaml:").unwrap().1.to_owned(),
        other => other.to_string(),
    })
}

#[test]
fn each_entry_becomes_its_command_line() {
    let rig = load(
        "devices:
  right: {kind: piper, iface: can_right, initial_joints_deg: [0, -10.5, 20], ui: 8001}
  left:
    kind: robot
    file: ../robots/humanoid.yaml
    create_vxcan: true
    state_file: left.json
  controller: {kind: realman, port: 8081, no_gripper: false}
",
    )
    .unwrap();
    let lines: Vec<(&str, SimKind, Vec<&str>)> = rig
        .devices
        .iter()
        .map(|d| {
            (
                d.name.as_str(),
                d.kind,
                d.args.iter().map(String::as_str).collect(),
            )
        })
        .collect();
    assert_eq!(
        lines,
        [
            ("controller", REALMAN, vec!["--port=8081"]),
            (
                "left",
                ROBOT,
                vec![
                    "--create-vxcan",
                    "--state-file=left.json",
                    "--",
                    "../robots/humanoid.yaml"
                ]
            ),
            (
                "right",
                PIPER,
                vec![
                    "--iface=can_right",
                    "--initial-joints-deg=0",
                    "--initial-joints-deg=-10.5",
                    "--initial-joints-deg=20",
                    "--ui=8001"
                ]
            ),
        ]
    );
}

#[test]
fn mistakes_are_named_at_their_line() {
    let cases = [
        ("devices:\n  a: {iface: can0}\n", "2:6: device `a`: no `kind:` (one of piper, realman, robstride, robot)"),
        ("devices:\n  a: {kind: pipr}\n", "2:13: device `a`: unknown kind `pipr`; did you mean `piper`?; a rig holds piper, realman, robstride, robot"),
        ("devices:\n  a: {kind: robot, file: [x1, x2]}\n", "2:26: device `a`: `file:` takes one value, not a list"),
        ("devices:\n  a: {kind: robstride, motor: [1:RS03, y]}\n", "2:31: an option's value is a word, a number, true/false or a list of words and numbers (quote a word YAML reads as something else, such as `y` or `no`)"),
        ("devices:\n  a: {kind: piper, ui: {port: 1}}\n", "2:24: an option's value is a word, a number, true/false or a list of words and numbers (quote a word YAML reads as something else, such as `y` or `no`)"),
        ("devices:\n  a: {kind: robot, file: true}\n", "2:26: device `a`: `file:` takes a value, not true"),
        ("devices:\n  a b: {kind: piper}\n", "2:8: device name `a b`: use 1 to 64 letters, digits, `_` or `-`"),
        ("devices: {}\n", "1:10: a rig needs at least one device"),
        ("device:\n  a: {kind: piper}\n", "1:1: unknown key `device`, expected one of devices; did you mean `devices`?"),
    ];
    for (text, want) in cases {
        let got = load(text).unwrap_err();
        assert_eq!(got, want, "{text}");
    }
}

#[test]
fn a_device_error_names_the_device_at_its_entry() {
    let (_dir, file) = write("devices:\n  left: {kind: piper, ifac: can0}\n");
    let rig = load_rig_file(&file, &KINDS).unwrap();
    let error = rig.devices[0].error("unexpected argument '--ifac'");
    assert!(
        error
            .headline()
            .ends_with(":2:9: device `left` (piper): unexpected argument '--ifac'"),
        "{}",
        error.headline()
    );
    assert_eq!(
        error.source_line.as_deref(),
        Some("  left: {kind: piper, ifac: can0}")
    );
}

#[test]
fn a_file_that_is_not_one_is_refused_without_reading_it_all() {
    let error = load_rig_file(std::path::Path::new("/dev/zero"), &KINDS).unwrap_err();
    assert!(error.to_string().contains("not a regular file"), "{error}");
}

/// The headline of a rig file's error (file:line:column: message).
fn headline(file: &std::path::Path) -> String {
    match load_rig_file(file, &KINDS) {
        Ok(_) => panic!("{} loaded", file.display()),
        Err(RigFileError::Invalid(e)) => e.headline(),
        Err(other) => panic!("{other}"),
    }
}

#[test]
fn two_devices_writing_one_file_are_refused_at_the_later_one() {
    // `a` sorts first but is written second: the message is at its value.
    let (dir, file) = write(
        "devices:
  b: {kind: piper, record: ./out/x.log}
  a:
    kind: robot
    file: r.yaml
    state_file: out/y/../x.log
",
    );
    assert_eq!(
        headline(&file),
        format!(
            "{}:6:17: device `a`: `state_file: out/y/../x.log` and device `b`'s `record:` \
             (line 2) are one file, {}: one would overwrite the other; give each its own file",
            file.display(),
            dir.path().join("out/x.log").display()
        )
    );
}

#[test]
fn one_device_writing_two_outputs_to_one_file_is_refused() {
    let (dir, file) = write("devices:\n  a: {kind: piper, state_file: a.json, record: a.json}\n");
    assert_eq!(
        headline(&file),
        format!(
            "{}:2:48: device `a`: `record: a.json` and its own `state_file:` (line 2) are one \
             file, {}: one would overwrite the other; give each its own file",
            file.display(),
            dir.path().join("a.json").display()
        )
    );
}

#[test]
fn an_output_given_as_a_list_of_one_is_that_file() {
    let got =
        load("devices:\n  a: {kind: piper, record: [x.log]}\n  b: {kind: piper, record: x.log}\n")
            .unwrap_err();
    assert!(
        got.starts_with("3:28: device `b`: `record: x.log` and device `a`'s `record:` (line 2)"),
        "{got}"
    );
}

#[test]
fn an_absolute_and_a_relative_name_of_one_file_are_one_file() {
    let (dir, file) = write("");
    let absolute = dir.path().join("s.json");
    std::fs::write(
        &file,
        format!(
            "devices:\n  a: {{kind: realman, state_file: {}}}\n  b: {{kind: robstride, state-file: s.json}}\n",
            absolute.display()
        ),
    )
    .unwrap();
    let got = headline(&file);
    assert!(
        got.contains(":3:")
            && got.contains("device `b`: `state_file: s.json` and device `a`'s `state_file:`"),
        "{got}"
    );
}

#[cfg(unix)]
#[test]
fn a_folder_reached_through_a_symbolic_link_is_the_same_folder() {
    let (dir, file) = write("devices:\n  a: {kind: piper, record: real/x.log}\n  b: {kind: piper, record: link/x.log}\n");
    std::fs::create_dir(dir.path().join("real")).unwrap();
    std::os::unix::fs::symlink(dir.path().join("real"), dir.path().join("link")).unwrap();
    let got = headline(&file);
    assert!(
        got.contains("device `b`: `record: link/x.log` and device `a`'s"),
        "{got}"
    );
}

#[test]
fn different_files_and_inputs_are_not_outputs() {
    // Same name in two folders; a URDF two devices read; an output left out (`false`).
    load(
        "devices:
  a: {kind: piper, record: l/x.log, state_file: a.json, urdf: arm.urdf}
  b: {kind: piper, record: r/x.log, state_file: b.json, urdf: ./arm.urdf}
  c: {kind: realman, state_file: false}
  d: {kind: realman, state_file: false}
",
    )
    .unwrap();
}
