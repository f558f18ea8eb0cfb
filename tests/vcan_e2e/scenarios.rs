//! `armhil run --iface` against a separate `armhil sim piper` process on a live vcan interface.
//!
//! Every scenario tagged `vcan` runs in real time against a fresh emulator process (started
//! with the scenario's firmware, so state from one scenario never leaks into the next). Those
//! scenarios include driver-visible faults that need no in-process hooks: the e-stop command,
//! a target past a joint limit, a MOVE P without IK solution, and feedback lost to a configured
//! leader. A scenario with injected faults must be reported as skipped, not failed.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

use armhil::harness::model::DeviceKind;
use armhil::harness::{discover, load_scenario};

fn iface() -> String {
    std::env::var("ARMHIL_VCAN_IFACE").unwrap_or_else(|_| "vcan0".to_owned())
}

fn armhil() -> PathBuf {
    std::env::var_os("ARMHIL_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_armhil")))
}

/// Outputs go under `ARMHIL_E2E_OUT` (the repo is read-only in the VM) or the temp dir.
fn out_dir() -> PathBuf {
    let base = std::env::var_os("ARMHIL_E2E_OUT")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    base.join(format!("scenarios-{}", std::process::id()))
}

/// An emulator process, killed (by its own handle) when dropped.
struct Sim(Child);

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Deadline factor and slack for `armhil run --time-scale F --deadline-slack-ms S` (the VM
/// runs several times slower than the host): `ARMHIL_E2E_TIME_SCALE` (default 150) and
/// `ARMHIL_E2E_DEADLINE_SLACK_MS` (default 3000). Only deadlines change (waits and holds do
/// not), so generous values cost time only when a scenario fails. Under TCG the emulator's
/// status stream (0x2A1, 200 Hz on hardware) was measured at 10–55 Hz with stalls of up to
/// 2.2 s, and with the emulator trying to keep wall-clock time a state change took more than
/// 3.5 s to show now and then: ×10 + 3 s failed four scenarios on their first attempt, ×150
/// passed them all. A failing 3 s wait then takes 7.5 minutes, the price of not flaking.
fn time_scale() -> String {
    std::env::var("ARMHIL_E2E_TIME_SCALE").unwrap_or_else(|_| "150".to_owned())
}

fn deadline_slack_ms() -> String {
    std::env::var("ARMHIL_E2E_DEADLINE_SLACK_MS").unwrap_or_else(|_| "3000".to_owned())
}

/// Wait until the emulator streams its status frame (0x2A1) on the interface.
fn wait_for_feedback() {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async {
        let bus = bus::socketcan_bus::SocketCanBus::open(&iface()).expect("interface opens");
        let seen = tokio::time::timeout(Duration::from_secs(60), async {
            loop {
                match bus::CanBus::recv(&bus).await {
                    Ok(f) if f.frame.raw_id() == 0x2A1 => break,
                    Ok(_) => {}
                    Err(e) => panic!("receive failed: {e}"),
                }
            }
        })
        .await;
        assert!(seen.is_ok(), "the emulator sent no 0x2A1 within 60 s");
        bus::CanBus::close(&bus).await;
    });
}

/// Start `armhil sim piper`; its log goes to `log` when given (read back when a scenario fails).
fn start_sim_logged(firmware: &str, log: Option<&Path>) -> Sim {
    let stderr = match log {
        Some(path) => {
            std::fs::create_dir_all(path.parent().expect("log path has a folder"))
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            Stdio::from(
                std::fs::File::create(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
            )
        }
        None => Stdio::null(),
    };
    // A TCG VM cannot run physics in real time: a catch-up of 100 ms of steps per wake once
    // starved the runner for seconds (an e-stop deadline of 6 s missed). The emulator's CPU
    // budget alone was not enough on a host busy with builds (the suite timed out), so the
    // suite also caps catch-up at 5 ms (ARMHIL_E2E_MAX_CATCH_UP_MS; empty for none).
    let catch_up_ms = std::env::var("ARMHIL_E2E_MAX_CATCH_UP_MS").unwrap_or_else(|_| "5".into());
    let mut command = Command::new(armhil());
    command.args(["sim", "piper", "--iface", &iface(), "--firmware", firmware]);
    if !catch_up_ms.is_empty() {
        command.args(["--max-catch-up-ms", &catch_up_ms]);
    }
    let child = command
        .stdout(Stdio::null())
        .stderr(stderr)
        .spawn()
        .expect("armhil sim piper starts");
    let sim = Sim(child);
    wait_for_feedback();
    sim
}

fn start_sim(firmware: &str) -> Sim {
    start_sim_logged(firmware, None)
}

fn run(file: &Path) -> Output {
    run_into(file, &out_dir())
}

/// `armhil run` of one file with its outputs under `out`.
fn run_into(file: &Path, out: &Path) -> Output {
    Command::new(armhil())
        .args([
            "run",
            "--iface",
            &iface(),
            "--time-scale",
            &time_scale(),
            "--deadline-slack-ms",
            &deadline_slack_ms(),
            "--out",
        ])
        .arg(out)
        .arg(file)
        .output()
        .expect("armhil run starts")
}

fn firmware_of(file: &Path) -> String {
    let scenario = load_scenario(file).unwrap_or_else(|e| panic!("{e}"));
    scenario
        .bench
        .devices
        .iter()
        .map(|d| match &d.kind {
            DeviceKind::Piper(p) => p.firmware.clone(),
            // Only Piper scenarios are tagged `vcan`: the other kinds need their in-process
            // emulators (a Realman arm is not on CAN at all).
            _ => String::new(),
        })
        .next()
        .expect("one device")
}

#[test]
#[ignore = "needs a live vcan interface (scripts/vcan-e2e.sh)"]
fn vcan_tagged_scenarios_pass_against_a_separate_emulator() {
    let files: Vec<PathBuf> = discover(&[PathBuf::from("scenarios")])
        .expect("scenarios/ readable")
        .into_iter()
        .filter(|f| load_scenario(f).map(|s| s.has_tag("vcan")).unwrap_or(false))
        .collect();
    assert!(
        files.len() >= 5,
        "expected at least 5 vcan scenarios, found {}",
        files.len()
    );
    for must in [
        "estop_command",
        "limit_violation",
        "move_p_unreachable",
        "leader_follower",
    ] {
        assert!(
            files
                .iter()
                .any(|f| f.file_stem().is_some_and(|s| s == must)),
            "{must} should be tagged vcan"
        );
    }
    let mut failed = Vec::new();
    let mut flaky = Vec::new();
    for file in &files {
        let first = attempt(file, 1);
        if first.passed {
            continue;
        }
        // Real time under TCG is at the mercy of the host's scheduler (see `time_scale`): a
        // failure is retried once against a fresh emulator, and both attempts are reported
        // with the emulator's status-stream figures so a stall can be told from a bug.
        eprintln!(
            "RETRY {}: first attempt failed\n{}",
            file.display(),
            first.report
        );
        let second = attempt(file, 2);
        if second.passed {
            flaky.push(format!("{}\n{}", file.display(), first.report));
        } else {
            failed.push(format!(
                "{}\n-- attempt 1 --\n{}\n-- attempt 2 --\n{}",
                file.display(),
                first.report,
                second.report
            ));
        }
    }
    if !flaky.is_empty() {
        eprintln!(
            "{} scenario(s) passed only on the retry:\n{}",
            flaky.len(),
            flaky.join("\n")
        );
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// One run of a scenario against a fresh emulator.
struct Attempt {
    passed: bool,
    /// On failure: the runner's output, the status-stream figures and the emulator log's tail.
    report: String,
}

fn attempt(file: &Path, number: u32) -> Attempt {
    let stem = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let out = out_dir().join(format!("attempt-{number}"));
    let sim_log = out.join(format!("{stem}.sim.log"));
    let sim = start_sim_logged(&firmware_of(file), Some(&sim_log));
    let output = run_into(file, &out);
    drop(sim);
    let stdout = String::from_utf8_lossy(&output.stdout);
    eprintln!("{stdout}");
    let passed =
        output.status.success() && stdout.starts_with("running on") && stdout.contains("PASS");
    if passed {
        return Attempt {
            passed,
            report: String::new(),
        };
    }
    let log = std::fs::read_to_string(&sim_log).unwrap_or_else(|e| format!("(no log: {e})"));
    let tail: Vec<&str> = log.lines().rev().take(15).collect();
    let report = format!(
        "{}\n{stdout}\n{}\n{}\nemulator log {} (last lines):\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr),
        status_stream_figures(&out.join(&stem).join("bus.log")),
        sim_log.display(),
        tail.into_iter().rev().collect::<Vec<_>>().join("\n")
    );
    Attempt { passed, report }
}

/// Rate and longest gap of the emulator's status frames (0x2A1) in a candump recording.
fn status_stream_figures(bus_log: &Path) -> String {
    let Ok(text) = std::fs::read_to_string(bus_log) else {
        return format!("{}: no recording", bus_log.display());
    };
    let stamps_s: Vec<f64> = text
        .lines()
        .filter_map(|line| {
            let mut fields = line.split_whitespace();
            let stamp = fields.next()?.trim_matches(|c| c == '(' || c == ')');
            let frame = fields.nth(1)?;
            frame
                .starts_with("2A1#")
                .then(|| stamp.parse::<f64>().ok())
                .flatten()
        })
        .collect();
    let (Some(first), Some(last)) = (stamps_s.first(), stamps_s.last()) else {
        return format!("{}: no 0x2A1 status frame recorded", bus_log.display());
    };
    let (gap_s, at_s) = stamps_s
        .windows(2)
        .map(|w| (w[1] - w[0], w[0] - first))
        .fold((0.0, 0.0), |best, g| if g.0 > best.0 { g } else { best });
    let span_s = last - first;
    format!(
        "status stream 0x2A1: {} frames in {span_s:.2} s ({:.0} Hz; 200 Hz on hardware), \
         longest gap {:.0} ms at {at_s:.2} s",
        stamps_s.len(),
        if span_s > 0.0 {
            (stamps_s.len() - 1) as f64 / span_s
        } else {
            0.0
        },
        gap_s * 1000.0
    )
}

#[test]
#[ignore = "needs a live vcan interface (scripts/vcan-e2e.sh)"]
fn scenarios_with_injected_faults_are_skipped_with_the_reason() {
    let _sim = start_sim("S-V1.8-8");
    let output = run(Path::new("scenarios/piper/fault_comm_loss.yaml"));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "a skip is not a failure:\n{stdout}"
    );
    assert!(
        stdout.contains("SKIP  fault_comm_loss: needs the in-process emulator"),
        "{stdout}"
    );
    assert!(stdout.contains("needs the in-process emulator"), "{stdout}");
    assert!(stdout.contains("comm_loss joint 3"), "{stdout}");
}

#[test]
fn status_stream_figures_find_the_longest_gap() {
    let dir = tempfile::tempdir().expect("temp dir");
    let log = dir.path().join("bus.log");
    std::fs::write(
        &log,
        "(100.000000) vcan0 2A1#0000000000000000\n\
         (100.005000) vcan0 150#0100000000000000\n\
         (100.010000) vcan0 2A1#0100000000000000\n\
         (101.210000) vcan0 2A1#0100000000000000\n\
         (101.215000) vcan0 2A1#0100000000000000\n",
    )
    .expect("write");
    let figures = status_stream_figures(&log);
    assert!(figures.contains("4 frames in 1.22 s"), "{figures}");
    assert!(
        figures.contains("longest gap 1200 ms at 0.01 s"),
        "{figures}"
    );
    assert!(status_stream_figures(&dir.path().join("none.log")).contains("no recording"));
}
