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

/// Deadline factor for `armhil run --time-scale` (the VM runs several times slower than the
/// host): `ARMHIL_E2E_TIME_SCALE`, default 60. Only deadlines are scaled (waits and holds are
/// not), so a generous factor costs time only when a scenario fails; at 25 an idle TCG VM still
/// missed a 50 ms status deadline now and then.
fn time_scale() -> String {
    std::env::var("ARMHIL_E2E_TIME_SCALE").unwrap_or_else(|_| "60".to_owned())
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

fn start_sim(firmware: &str) -> Sim {
    let child = Command::new(armhil())
        .args(["sim", "piper", "--iface", &iface(), "--firmware", firmware])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("armhil sim piper starts");
    let sim = Sim(child);
    wait_for_feedback();
    sim
}

fn run(file: &Path) -> Output {
    Command::new(armhil())
        .args([
            "run",
            "--iface",
            &iface(),
            "--time-scale",
            &time_scale(),
            "--out",
        ])
        .arg(out_dir())
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
            // RobStride and Realman scenarios are not tagged `vcan` (they need the in-process
            // emulator; a Realman arm is not on CAN at all).
            DeviceKind::Robstride(_) | DeviceKind::Realman(_) => String::new(),
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
    for file in &files {
        let _sim = start_sim(&firmware_of(file));
        let output = run(file);
        let stdout = String::from_utf8_lossy(&output.stdout);
        eprintln!("{stdout}");
        if !output.status.success() || !stdout.starts_with("running on") || !stdout.contains("PASS")
        {
            failed.push(format!(
                "{}: {}\n{stdout}\n{}",
                file.display(),
                output.status,
                String::from_utf8_lossy(&output.stderr)
            ));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
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
