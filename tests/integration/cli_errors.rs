//! The `armhil` binary under bad input: clear errors naming the option or path, never a panic
//! (exit 101) and never a silent success.

use std::path::Path;
use std::process::{Command, Output};

const ARMHIL: &str = env!("CARGO_BIN_EXE_armhil");

fn armhil(args: &[&str]) -> Output {
    Command::new(ARMHIL)
        .args(args)
        .output()
        .expect("armhil runs")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn replay_with_an_absurd_speed_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("x.log");
    std::fs::write(&log, "(1.000000) vcan0 123#00\n(2.000000) vcan0 123#01\n").unwrap();
    let out = armhil(&[
        "replay",
        log.to_str().unwrap(),
        "--iface",
        "armhil-nosuch",
        "--speed",
        "1e-300",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("--speed 1e-300"), "{}", stderr(&out));
}

#[test]
fn record_with_an_absurd_duration_is_an_error_not_a_panic() {
    let out = armhil(&[
        "record",
        "--iface",
        "armhil-nosuch",
        "-o",
        "/nonexistent/x.log",
        "--duration",
        "1e300",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("--duration"), "{}", stderr(&out));
}

#[test]
fn record_reports_a_bad_output_path_before_opening_the_interface() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("missing-folder").join("x.log");
    let output = output.to_str().unwrap();
    let out = armhil(&["record", "--iface", "armhil-nosuch", "-o", output]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let text = stderr(&out);
    assert!(text.contains(output), "{text}");
    assert!(!text.contains("armhil-nosuch"), "{text}");
    // The I/O error is said once.
    assert_eq!(text.matches("os error 2").count(), 1, "{text}");
}

fn scenario(dir: &Path) -> String {
    let path = dir.join("tiny.yaml");
    std::fs::write(
        &path,
        "bench:\n  devices:\n    arm: {kind: piper}\nsteps:\n  - wait_ms: 1\n",
    )
    .unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn an_unwritable_junit_path_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let file = scenario(dir.path());
    let out_dir = dir.path().join("out");
    // Under a regular file, so not even root can create it.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, "").unwrap();
    let junit = blocker.join("report.xml");
    let out = armhil(&[
        "run",
        &file,
        "--out",
        out_dir.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(junit.to_str().unwrap()),
        "{}",
        stderr(&out)
    );
}

#[test]
fn outputs_that_cannot_be_written_fail_the_run_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let file = scenario(dir.path());
    // The output root is a regular file, so no folder can be created under it.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, "").unwrap();
    let out = armhil(&["run", &file, "--out", blocker.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains(blocker.to_str().unwrap()), "{stdout}");
}

/// A rig file with `ifac:` for `iface:` on its third line, and where it is.
fn rig_with_a_misspelt_option() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rig.yaml");
    std::fs::write(
        &file,
        "devices:\n  left: {kind: realman, port: 1}\n  right: {kind: piper, ifac: can0}\n",
    )
    .unwrap();
    (dir, file)
}

#[test]
fn a_rig_file_s_mistakes_are_named_at_the_device_s_line() {
    let (_dir, file) = rig_with_a_misspelt_option();
    let out = armhil(&["sim", "rig", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(
            "rig.yaml:3:10: device `right` (piper): unexpected argument `ifac:` found; tip: a \
             similar argument exists: `iface:`"
        ),
        "{}",
        stderr(&out)
    );
}

/// `armhil sim bench FILE`, the command's name before rig files were called so, still runs
/// one (a hidden alias: `armhil sim --help` does not list it).
#[test]
fn sim_bench_is_still_sim_rig() {
    let (_dir, file) = rig_with_a_misspelt_option();
    let out = armhil(&["sim", "bench", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("rig.yaml:3:10: device `right` (piper): unexpected argument"),
        "{}",
        stderr(&out)
    );
    let help = armhil(&["sim", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("rig") && !help.contains("bench"), "{help}");
}

#[test]
fn a_rig_whose_device_cannot_start_stops_the_others_and_says_which() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rig.yaml");
    let free = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    std::fs::write(
        &file,
        format!("devices:\n  a: {{kind: realman, port: {free}}}\n  b: {{kind: realman, port: {port}}}\n"),
    )
    .unwrap();
    let out = armhil(&["sim", "rig", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(&format!(
            "1 of 2 devices of {} failed:\n  device `b` (realman): cannot start the Realman emulator on 127.0.0.1:{port}",
            file.display()
        )),
        "{}",
        stderr(&out)
    );
}

#[test]
fn one_scenario_under_an_out_that_is_a_file_counts_one_failed_write() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not_a_folder");
    std::fs::write(&file, "").unwrap();
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/piper/showcase.yaml");
    let out = armhil(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{stdout}");
    assert!(
        stdout.contains("1 scenario(s) could not write their outputs"),
        "{stdout}"
    );
    assert!(
        stdout.contains("the suite's index could not be written"),
        "{stdout}"
    );
    assert!(!stdout.contains("2 scenario(s)"), "{stdout}");
}
