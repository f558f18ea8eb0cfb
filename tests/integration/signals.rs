//! SIGINT and SIGTERM at any moment leave complete, readable files: `armhil run` writes the
//! interrupted scenario's outputs and the JUnit report, `armhil sim piper --record` and
//! `armhil record` finish their candump logs and pcaps. On the host through the virtual bus
//! and socketcand; the SocketCAN variants run in the vcan VM suite.

use std::ffi::OsStr;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::Duration;

use super::support::{start_sim, ARMHIL};

/// The moments (after start) the signals are sent: early, while setting up, mid-run.
const MOMENTS_MS: [u64; 3] = [150, 700, 2000];

/// From this moment on each command must have its signal handlers in place: dying of the
/// signal (no exit code) fails the test.
const LISTENING_BY_MS: u64 = 700;

/// Whether the process died of the signal itself (before it listened), which is only
/// accepted early on.
fn killed_early(status: ExitStatus, moment_ms: u64, what: &str) -> bool {
    if status.code().is_some() {
        return false;
    }
    assert!(
        moment_ms < LISTENING_BY_MS,
        "{what}: the process died of the signal instead of finishing its files"
    );
    true
}

fn send(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args([format!("-{signal}"), child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success(), "kill -{signal} failed");
}

/// Send `signal` after `after`, then wait (at most 60 s) for the process to end.
fn stop(mut child: Child, signal: &str, after: Duration) -> ExitStatus {
    std::thread::sleep(after);
    send(&child, signal);
    for _ in 0..600 {
        if let Some(status) = child.try_wait().expect("wait works") {
            return status;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let _ = child.kill();
    panic!("the process did not stop within 60 s of {signal}");
}

/// A candump log every line of which reads back (none cut short).
fn assert_complete_candump(path: &Path) -> usize {
    let entries = bus::candump::read_log(path)
        .unwrap_or_else(|e| panic!("{} is not a complete candump log: {e}", path.display()));
    let text = std::fs::read_to_string(path).unwrap();
    assert!(
        text.is_empty() || text.ends_with('\n'),
        "{} ends mid-line",
        path.display()
    );
    entries.len()
}

/// A pcap every record of which reads back.
fn assert_complete_pcap(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    bus::pcap::parse_capture(&bytes)
        .unwrap_or_else(|e| panic!("{} is not a complete pcap: {e:?}", path.display()))
        .len()
}

/// A candump log or a pcap (by extension) that reads back whole; its frame count.
fn assert_complete_recording(path: &Path) -> usize {
    if path.extension().is_some_and(|e| e == "pcap") {
        assert_complete_pcap(path)
    } else {
        assert_complete_candump(path)
    }
}

/// `armhil ARGS` with its output discarded, sent `SIG<signal>` after `moment_ms`: its exit
/// status, or `None` when it died of the signal before listening for it.
fn signalled(args: &[&OsStr], signal: &str, moment_ms: u64) -> (Option<ExitStatus>, String) {
    let child = Command::new(ARMHIL)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let status = stop(child, signal, Duration::from_millis(moment_ms));
    let what = format!("SIG{signal} after {moment_ms} ms");
    let status = (!killed_early(status, moment_ms, &what)).then_some(status);
    (status, what)
}

fn scenario(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("long.yaml");
    std::fs::write(
        &path,
        "name: long\nbench:\n  devices:\n    arm: {kind: piper}\nrecord: {candump: true, pcap: true}\nsteps:\n  - enable: {}\n  - wait_ms: 600000\n",
    )
    .unwrap();
    path
}

#[test]
fn an_interrupted_run_still_writes_complete_outputs() {
    for signal in ["INT", "TERM"] {
        for moment in MOMENTS_MS {
            let dir = tempfile::tempdir().unwrap();
            let file = scenario(dir.path());
            let out = dir.path().join("out");
            let junit = dir.path().join("junit.xml");
            let args = [
                "run".as_ref(),
                "--out".as_ref(),
                out.as_os_str(),
                "--junit".as_ref(),
                junit.as_os_str(),
                file.as_os_str(),
            ];
            let (Some(status), what) = signalled(&args, signal, moment) else {
                // Killed before the handler was installed: nothing may have been written.
                assert!(!out.exists() && !junit.exists(), "files from a killed run");
                continue;
            };
            assert_eq!(status.code(), Some(130), "{what}");
            let result = std::fs::read_to_string(out.join("long/result.yaml")).unwrap();
            assert!(
                result.contains(&format!("interrupted by SIG{signal}")),
                "{what}: {result}"
            );
            let frames = assert_complete_candump(&out.join("long/bus.log"));
            assert_eq!(
                assert_complete_pcap(&out.join("long/bus.pcap")),
                frames,
                "{what}: the two recordings differ"
            );
            let xml = std::fs::read_to_string(&junit).unwrap();
            assert!(xml.trim_end().ends_with("</testsuites>"), "{what}: {xml}");
            assert!(xml.contains("interrupted by"), "{what}: {xml}");
        }
    }
}

#[test]
fn an_emulator_stopped_by_a_signal_finishes_its_recording() {
    for (signal, name) in [("INT", "sim.log"), ("TERM", "sim.pcap")] {
        for moment in MOMENTS_MS {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join(name);
            let addr = format!("127.0.0.1:{}", super::support::free_port());
            let args = [
                "sim".as_ref(),
                "piper".as_ref(),
                "--socketcand".as_ref(),
                addr.as_ref(),
                "--record".as_ref(),
                path.as_os_str(),
            ];
            let (Some(status), what) = signalled(&args, signal, moment) else {
                continue; // Killed before it listened for signals (no recording started).
            };
            assert_eq!(status.code(), Some(0), "{what}");
            let frames = assert_complete_recording(&path);
            if moment >= 700 {
                assert!(frames > 100, "{what}: only {frames} frames recorded");
            }
        }
    }
}

#[test]
fn a_recording_stopped_by_a_signal_is_complete() {
    let (_sim, addr) = start_sim(&["piper"]);
    for (signal, name) in [("INT", "rec.pcap"), ("TERM", "rec.log")] {
        for moment in MOMENTS_MS {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join(name);
            let args = [
                "record".as_ref(),
                "--socketcand".as_ref(),
                addr.as_ref(),
                "-o".as_ref(),
                path.as_os_str(),
            ];
            let (Some(status), what) = signalled(&args, signal, moment) else {
                continue;
            };
            assert_eq!(status.code(), Some(0), "{what}");
            let frames = assert_complete_recording(&path);
            if moment >= 2000 {
                assert!(frames > 100, "{what}: only {frames} frames recorded");
            }
        }
    }
}

/// Every file under `dir` (recursively) whose name is hidden and looks temporary.
fn hidden_temporaries(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return found;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            found.extend(hidden_temporaries(&path));
        } else if path
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with('.') && n.contains(".tmp"))
        {
            found.push(path);
        }
    }
    found
}

/// Wait (at most 60 s) for `child` to end.
fn wait_for_exit(child: &mut Child, what: &str) -> ExitStatus {
    for _ in 0..600 {
        if let Some(status) = child.try_wait().expect("wait works") {
            return status;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let _ = child.kill();
    panic!("{what}: the process did not end within 60 s");
}

#[test]
fn a_second_signal_quits_at_once_and_leaves_no_temporary_file() {
    // The second signal comes while the first one's outputs are being finished: the spool
    // files (in TMPDIR) and any output being written exist only under temporary names then.
    for gap_ms in [2, 30, 150] {
        let dir = tempfile::tempdir().unwrap();
        let file = scenario(dir.path());
        let out = dir.path().join("out");
        let tmp = dir.path().join("tmp");
        std::fs::create_dir(&tmp).unwrap();
        let args: [&OsStr; 4] = [
            "run".as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
            file.as_os_str(),
        ];
        let mut child = Command::new(ARMHIL)
            .args(args)
            .env("TMPDIR", &tmp)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(2000));
        send(&child, "INT");
        std::thread::sleep(Duration::from_millis(gap_ms));
        send(&child, "INT");
        let what = format!("a second SIGINT {gap_ms} ms after the first");
        let status = wait_for_exit(&mut child, &what);
        assert_eq!(status.code(), Some(130), "{what}");
        let left: Vec<_> = std::fs::read_dir(&tmp)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        assert!(left.is_empty(), "{what}: spool files left behind: {left:?}");
        let hidden = hidden_temporaries(&out);
        assert!(
            hidden.is_empty(),
            "{what}: temporary outputs left: {hidden:?}"
        );
    }
}

/// Start `armhil sim ARGS`, which must refuse to start: it exits 1 on its own. Its stderr.
fn refused_at_start(dir: &Path, args: &[&OsStr], what: &str) -> String {
    let (mut child, log) = sim_logging_to(dir, args);
    let status = wait_for_exit(&mut child, what);
    let stderr = std::fs::read_to_string(&log).unwrap();
    assert_eq!(status.code(), Some(1), "{stderr}");
    stderr
}

/// `armhil sim ARGS` with its stderr in a file; the process and that file.
fn sim_logging_to(dir: &Path, args: &[&OsStr]) -> (Child, std::path::PathBuf) {
    let log = dir.join("stderr.txt");
    let child = Command::new(ARMHIL)
        .arg("sim")
        .args(args)
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&log).unwrap())
        .spawn()
        .unwrap();
    (child, log)
}

/// Connect to `addr` within 20 s (the emulator is up), unless `child` exits first.
fn connect(addr: &str, child: &mut Child) -> std::net::TcpStream {
    for _ in 0..400 {
        if let Ok(stream) = std::net::TcpStream::connect(addr) {
            // Not a TCP self-connect (see `support::listens`).
            if stream.local_addr().ok() != stream.peer_addr().ok() {
                return stream;
            }
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the emulator exited before listening"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!("nothing listens on {addr}");
}

#[test]
fn a_state_file_that_cannot_be_written_makes_the_emulator_exit_non_zero_naming_it() {
    use std::io::{Read, Write};

    // Piper: the file is written when a parameter changes; its folder does not exist. The
    // emulator must stop serving and exit non-zero at once, not serve a dead bus.
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("removed").join("piper-flash.json");
    let addr = format!("127.0.0.1:{}", super::support::free_port());
    let args = [
        "piper".as_ref(),
        "--socketcand".as_ref(),
        addr.as_ref(),
        "--state-file".as_ref(),
        state.as_os_str(),
    ];
    let (mut child, log) = sim_logging_to(dir.path(), &args);
    let mut stream = connect(&addr, &mut child);
    stream
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    let mut hello = [0u8; 6];
    stream.read_exact(&mut hello).unwrap();
    assert_eq!(&hello, b"< hi >");
    // 0x47A: collision levels, kept in flash.
    stream
        .write_all(b"< open can0 >< send 47A 8 03 03 03 03 03 03 00 00 >")
        .unwrap();
    let status = wait_for_exit(&mut child, "Piper with an unwritable state file");
    let stderr = std::fs::read_to_string(&log).unwrap();
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("piper-flash.json"), "{stderr}");

    // Realman: the file is written at exit (D19: this exited 0).
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("removed").join("realman-settings.json");
    let port = super::support::free_port().to_string();
    let args = [
        "realman".as_ref(),
        "--port".as_ref(),
        port.as_ref(),
        "--state-file".as_ref(),
        state.as_os_str(),
    ];
    let (mut child, log) = sim_logging_to(dir.path(), &args);
    drop(connect(&format!("127.0.0.1:{port}"), &mut child));
    send(&child, "INT");
    let status = wait_for_exit(&mut child, "Realman with an unwritable state file");
    let stderr = std::fs::read_to_string(&log).unwrap();
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("realman-settings.json"), "{stderr}");
}

#[test]
fn a_state_file_the_commands_would_refuse_is_refused_at_start_naming_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    // D4: min above max on joint 3 panicked the Piper's core at the first move.
    let flash = serde_json::json!({
        "min_angle_ddeg": [-1500, 0, 100, -890, -890, -1800],
        "max_angle_ddeg": [1500, 1800, 0, 890, 890, 1800],
    });
    let piper = dir.path().join("piper.json");
    std::fs::write(
        &piper,
        serde_json::json!({"kind": "piper", "format": 1, "flash": flash}).to_string(),
    )
    .unwrap();
    let addr = format!("127.0.0.1:{}", super::support::free_port());
    let args = [
        "piper".as_ref(),
        "--socketcand".as_ref(),
        addr.as_ref(),
        "--state-file".as_ref(),
        piper.as_os_str(),
    ];
    let stderr = refused_at_start(dir.path(), &args, "Piper with min above max");
    assert!(
        stderr.contains("piper.json") && stderr.contains("flash.min_angle_ddeg[2]"),
        "{stderr}"
    );

    // D16: the Piper's file given to the Realman emulator.
    let port = super::support::free_port().to_string();
    let args = [
        "realman".as_ref(),
        "--port".as_ref(),
        port.as_ref(),
        "--state-file".as_ref(),
        piper.as_os_str(),
    ];
    let stderr = refused_at_start(dir.path(), &args, "Realman given a Piper file");
    assert!(
        stderr.contains("piper.json") && stderr.contains("`kind`"),
        "{stderr}"
    );
}

#[test]
fn ctrl_c_while_a_large_robot_loads_ends_the_process_at_once() {
    // A 30,000-link chain (11 MB, about 2.5 s to load in the test profile): Ctrl-C 0.5 s in
    // ends the process while it is still loading (exit 130), not once it has loaded.
    let dir = tempfile::tempdir().unwrap();
    let mut urdf = String::from("<robot name=\"chain\">\n");
    let inertial = r#"<inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>"#;
    for i in 0..30_000 {
        urdf.push_str(&format!("<link name=\"l{i}\">{inertial}</link>\n"));
        if i > 0 {
            urdf.push_str(&format!(
                "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/><origin xyz=\"0 0 0.01\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
                i - 1
            ));
        }
    }
    urdf.push_str("</robot>\n");
    std::fs::write(dir.path().join("chain.urdf"), urdf).unwrap();
    let robot = dir.path().join("chain.yaml");
    std::fs::write(
        &robot,
        "robot: chain\nurdf: chain.urdf\nbuses: [{name: can0}]\nactuators:\n  - {joint: j1, model: RS03, id: 1, bus: can0}\n",
    )
    .unwrap();
    let child = Command::new(ARMHIL)
        .args([OsStr::new("sim"), OsStr::new("robot"), robot.as_os_str()])
        .args(["--socketcand", "127.0.0.1:0"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("armhil runs");
    let started = std::time::Instant::now();
    let status = stop(child, "INT", Duration::from_millis(500));
    let took = started.elapsed();
    assert_eq!(status.code(), Some(130), "exit {status:?}");
    assert!(took < Duration::from_millis(1500), "stopped after {took:?}");
}
