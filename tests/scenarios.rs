//! Scenario tests: every scenario under `scenarios/` against its committed insta snapshot, a
//! determinism check (two runs, identical bytes), and broken scenarios whose errors must name
//! the file, line and column.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use armhil::harness::report::{plot_svg, snapshot_yaml};
use armhil::harness::{
    discover, load_scenario, parse_scenario, run_scenario, Clock, ScenarioResult, Verdict,
};

fn scenario_files() -> Vec<PathBuf> {
    let files = discover(&[PathBuf::from("scenarios")]).expect("scenarios/ is readable");
    assert!(
        files.len() >= 26,
        "expected the full suite, found {} files",
        files.len()
    );
    files
}

/// Snapshot name: the path under `scenarios/` without extension, `/` → `__`.
fn snapshot_name(path: &Path) -> String {
    let rel = path
        .strip_prefix("scenarios")
        .unwrap_or(path)
        .with_extension("");
    rel.to_string_lossy().replace(['/', '\\'], "__")
}

/// Run every scenario on two threads (each run has its own virtual-time runtime).
fn run_all(files: &[PathBuf]) -> Vec<(PathBuf, ScenarioResult)> {
    let mut out: Vec<(usize, PathBuf, ScenarioResult)> = Vec::new();
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..2)
            .map(|worker| {
                scope.spawn(move || {
                    let mut mine = Vec::new();
                    for (i, file) in files.iter().enumerate().filter(|(i, _)| i % 2 == worker) {
                        let scenario = load_scenario(file).unwrap_or_else(|e| panic!("{e}"));
                        mine.push((i, file.clone(), run_scenario(&scenario, &Clock::Virtual)));
                    }
                    mine
                })
            })
            .collect();
        for h in handles {
            out.extend(h.join().expect("worker thread"));
        }
    });
    out.sort_by_key(|(i, _, _)| *i);
    out.into_iter().map(|(_, f, r)| (f, r)).collect()
}

#[test]
fn every_scenario_passes_and_matches_its_snapshot() {
    let files = scenario_files();
    let wall = std::time::Instant::now();
    let results = run_all(&files);
    let wall = wall.elapsed();
    let scenario_time: std::time::Duration = results.iter().map(|(_, r)| r.duration).sum();
    eprintln!(
        "{} scenarios: {:.1} s scenario time in {:.2} s wall (x{:.1})",
        results.len(),
        scenario_time.as_secs_f64(),
        wall.as_secs_f64(),
        scenario_time.as_secs_f64() / wall.as_secs_f64()
    );
    let mut failures = Vec::new();
    for (file, result) in &results {
        if result.verdict != Verdict::Passed {
            failures.push(format!(
                "{}: verdict {:?}\n{}",
                file.display(),
                result.verdict,
                snapshot_yaml(result)
            ));
            continue;
        }
        let name = snapshot_name(file);
        let text = snapshot_yaml(result);
        let check = catch_unwind(AssertUnwindSafe(|| {
            insta::with_settings!({ prepend_module_to_snapshot => false, omit_expression => true }, {
                insta::assert_snapshot!(name.as_str(), text);
            });
        }));
        if check.is_err() {
            failures.push(format!("{}: snapshot `{name}` differs", file.display()));
        }
    }
    assert!(
        failures.is_empty(),
        "{} scenario(s) failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn runs_are_deterministic_to_the_byte() {
    let files = scenario_files();
    let first = run_all(&files);
    let second = run_all(&files);
    for ((file, a), (_, b)) in first.iter().zip(&second) {
        assert_eq!(
            snapshot_yaml(a),
            snapshot_yaml(b),
            "{}: snapshot differs between runs",
            file.display()
        );
        assert_eq!(
            plot_svg(a),
            plot_svg(b),
            "{}: plot differs between runs",
            file.display()
        );
        assert_eq!(
            a.frames,
            b.frames,
            "{}: bus recording differs between runs",
            file.display()
        );
        let dir_a = tempdir(&format!("det-a-{}", snapshot_name(file)));
        let dir_b = tempdir(&format!("det-b-{}", snapshot_name(file)));
        let scenario = load_scenario(file).expect("loads");
        armhil::harness::report::write_outputs(a, &scenario.record, &dir_a).expect("writes");
        armhil::harness::report::write_outputs(b, &scenario.record, &dir_b).expect("writes");
        for name in ["result.yaml", "bus.log", "bus.pcap", "plot.svg"] {
            let (x, y) = (
                std::fs::read(dir_a.join(name)),
                std::fs::read(dir_b.join(name)),
            );
            if let (Ok(x), Ok(y)) = (x, y) {
                assert!(x == y, "{}: {name} differs between runs", file.display());
            }
        }
    }
}

fn tempdir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("armhil-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

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
        "broken.yaml:5:46: unknown key `sped_pct`, expected one of device, id, timeout_ms, expect_error, joints_deg, speed_pct; did you mean `speed_pct`?"
    );
}

#[test]
fn typo_in_a_top_level_key_is_an_error() {
    let text = format!("{BENCH}step:\n  - estop\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:4:1: unknown key `step`, expected one of name, description, tags, bench, record, faults, steps; did you mean `steps`?"
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
