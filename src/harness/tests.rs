//! Unit tests of the two parsing layers and the report writers.

use std::path::Path;
use std::time::Duration;

use super::model::*;
use super::parse_scenario;
use super::report::{junit_xml, write_atomic};
use super::result::{Outcome, ScenarioResult, StepResult, Verdict};
use super::test_support::error_of as error;
use crate::devices::piper::model::{Check as PiperCheck, PiperAction};

fn parse(text: &str) -> Scenario {
    parse_scenario(Path::new("t.yaml"), text).unwrap_or_else(|e| panic!("{e}"))
}

const BENCH: &str = "bench:\n  devices:\n    arm: {kind: piper}\n";

#[test]
fn bare_and_mapping_forms_give_the_same_action() {
    let s = parse(&format!(
        "{BENCH}steps:\n  - estop\n  - estop:\n  - estop: {{device: arm}}\n"
    ));
    assert_eq!(s.steps.len(), 3);
    for step in &s.steps {
        assert!(matches!(
            step.kind,
            StepKind::Action {
                device: 0,
                action: Action::Piper(PiperAction::Estop),
                timeout: None,
                expect_error: None
            }
        ));
    }
    assert_eq!(s.steps[1].line, 6);
}

#[test]
fn defaults_and_units_are_applied() {
    let s = parse(&format!(
        "{BENCH}steps:\n  - move_j: {{joints_deg: [90, 0, 0, 0, 0, 0]}}\n  - wait_until: {{joints_deg: [90, ~, ~, ~, ~, ~], timeout_ms: 250}}\n"
    ));
    assert_eq!(s.name, "t");
    assert_eq!(s.record.sample_period, Duration::from_millis(50));
    let StepKind::Action {
        action:
            Action::Piper(PiperAction::MoveJ {
                joints_deg,
                speed_pct,
                every_ms: None,
            }),
        ..
    } = &s.steps[0].kind
    else {
        panic!("move_j expected");
    };
    assert_eq!(joints_deg[0], 90.0);
    assert_eq!(*speed_pct, 50);
    let StepKind::WaitUntil {
        checks, timeout, ..
    } = &s.steps[1].kind
    else {
        panic!("wait_until expected")
    };
    assert_eq!(*timeout, Duration::from_millis(250));
    assert_eq!(
        checks,
        &vec![Check::Piper(PiperCheck::JointsNear {
            targets_deg: vec![Some(90.0), None, None, None, None, None],
            tolerance_deg: 0.5
        })]
    );
}

#[test]
fn schedule_after_a_step_resolves_the_step_index() {
    let s = parse(&format!(
        "{BENCH}faults:\n  - {{after: go, delay_ms: 20, duration_ms: 100, fault: {{drop: {{id: 0x2A5}}}}}}\nsteps:\n  - wait_ms: 1\n  - enable: {{id: go}}\n"
    ));
    assert_eq!(s.faults.len(), 1);
    assert_eq!(
        s.faults[0].trigger,
        FaultTrigger::AfterStep {
            step: 1,
            delay: Duration::from_millis(20)
        }
    );
    assert_eq!(s.faults[0].duration, Some(Duration::from_millis(100)));
    assert_eq!(
        s.faults[0].fault,
        FaultSpec::Bus {
            bus: 0,
            fault: BusFault::Drop {
                frames: FrameSelector::Id(0x2A5),
                probability: None
            }
        }
    );
}

#[test]
fn arm_status_accepts_names_and_codes() {
    let s = parse(&format!("{BENCH}steps:\n  - expect: {{arm_status: 0x04}}\n  - expect: {{arm_status: angle_limit}}\n"));
    for step in &s.steps {
        let StepKind::Expect { checks, .. } = &step.kind else {
            panic!()
        };
        assert_eq!(
            checks,
            &vec![Check::Piper(PiperCheck::Status {
                field: "arm_status",
                value: "angle_limit".to_owned()
            })]
        );
    }
}

#[test]
fn semantic_errors_point_at_the_value() {
    assert_eq!(
        error(&format!("{BENCH}steps:\n  - mode: {{move: x}}\n")),
        "broken.yaml:5:18: `move`: unknown value `x`; expected one of: p, j, l, c, m"
    );
    assert_eq!(
        error(&format!(
            "{BENCH}steps:\n  - inject: {{fault: {{estop: {{joint: 2}}}}}}\n"
        )),
        "broken.yaml:5:37: `estop` takes no `joint` (it takes: no arguments)"
    );
    assert_eq!(
        error(&format!(
            "{BENCH}steps:\n  - inject: {{fault: {{bus_off: {{node: host}}}}}}\n"
        )),
        "broken.yaml:5:5: `bus_off` needs `duration_ms` (the node recovers after it)"
    );
    assert_eq!(
        error(&format!(
            "{BENCH}steps:\n  - inject: {{fault: {{silence: {{node: left}}}}}}\n"
        )),
        "broken.yaml:5:38: unknown node `left`; expected `host` (the driver) or a device: arm"
    );
    assert_eq!(
        error(&format!("{BENCH}steps:\n  - expect: {{}}\n")),
        "broken.yaml:5:5: `expect` has no condition (for example `joints_deg`, `arm_status`, `enabled`)"
    );
    assert_eq!(
        error(&format!("{BENCH}steps:\n  - move_j: {{speed_pct: 20}}\n")),
        "broken.yaml:5:5: `move_j` needs `joints_deg`"
    );
    assert_eq!(
        error(&format!("{BENCH}steps:\n  - estop: {{}}\n    reset:\n")),
        "broken.yaml:5:5: one step per list item, found a second key `reset` (indent its arguments under `estop:`)"
    );
}

#[test]
fn several_devices_need_a_device_key() {
    let text =
        "bench:\n  devices:\n    a: {kind: piper}\n    b: {kind: piper}\nsteps:\n  - estop\n";
    assert_eq!(
        error(text),
        "broken.yaml:6:5: the bench has several devices (a, b): say which with `device:`"
    );
}

fn result(verdict: Verdict, outcome: Outcome) -> ScenarioResult {
    let mut r = ScenarioResult::not_run(
        "demo",
        "scenarios/piper/demo.yaml".into(),
        verdict,
        "virtual",
    );
    r.steps.push(StepResult {
        index: 0,
        line: 7,
        label: "wait_until".to_owned(),
        id: None,
        started: Duration::ZERO,
        took: Duration::from_millis(50),
        outcome,
        reply: Vec::new(),
    });
    r
}

#[test]
fn junit_reports_failures_with_expected_and_actual() {
    let failed = result(
        Verdict::Failed,
        Outcome::TimedOut {
            waited: Duration::from_millis(50),
            expected: "arm_status estop".into(),
            actual: "arm_status normal".into(),
        },
    );
    let passed = result(Verdict::Passed, Outcome::Passed);
    let xml = junit_xml("armhil", &[failed, passed]).expect("serialises");
    for attr in [r#"tests="2""#, r#"failures="1""#, r#"errors="0""#] {
        assert!(xml.contains(attr), "{attr} in {xml}");
    }
    assert!(
        xml.contains(r#"message="step 1 (wait_until, line 7) timed out""#),
        "{xml}"
    );
    assert!(xml.contains("waited 50 ms"), "{xml}");
    assert!(
        xml.contains("expected: arm_status estop\nactual: arm_status normal"),
        "{xml}"
    );
    assert!(xml.contains(r#"classname="scenarios.piper""#), "{xml}");
}

#[test]
fn atomic_write_replaces_the_file_and_leaves_no_temp() {
    let tmp = tempfile::tempdir().expect("a temp dir");
    let dir = tmp.path();
    let path = dir.join("sub").join("f.txt");
    write_atomic(&path, b"one").expect("first write");
    write_atomic(&path, b"two").expect("second write");
    assert_eq!(std::fs::read(&path).expect("readable"), b"two");
    let leftovers: Vec<_> = std::fs::read_dir(dir.join("sub")).expect("dir").collect();
    assert_eq!(leftovers.len(), 1);
}

#[test]
fn every_ms_is_read_and_range_checked() {
    let s = parse(&format!(
        "{BENCH}steps:\n  - move_l: {{position_mm: [150, 0, 250], orientation_deg: [0, 85, 0], every_ms: 5}}\n  - gripper: {{stroke_mm: 10}}\n"
    ));
    let StepKind::Action {
        action: Action::Piper(PiperAction::MoveL { every_ms, .. }),
        ..
    } = &s.steps[0].kind
    else {
        panic!("move_l expected");
    };
    assert_eq!(*every_ms, Some(5));
    let StepKind::Action {
        action: Action::Piper(PiperAction::Gripper { every_ms, .. }),
        ..
    } = &s.steps[1].kind
    else {
        panic!("gripper expected");
    };
    assert_eq!(*every_ms, None);
    assert_eq!(
        error(&format!(
            "{BENCH}steps:\n  - move_j: {{joints_deg: [0, 0, 0, 0, 0, 0], every_ms: 0}}\n"
        )),
        "broken.yaml:5:56: `every_ms` must be 1..=10000, got 0"
    );
}

/// The Piper's URDF with every link `factor` times lighter (mass and inertia).
fn lighter_piper(factor: f64) -> String {
    let mut out = String::new();
    for line in sim::piper::BUNDLED_URDF.lines() {
        let scaled = if line.contains("<mass ") || line.contains("<inertia ") {
            let mut l = String::new();
            for (i, part) in line.split('"').enumerate() {
                if i % 2 == 1 {
                    match part.parse::<f64>() {
                        Ok(v) => l.push_str(&format!("{:e}", v / factor)),
                        Err(_) => l.push_str(part),
                    }
                } else {
                    l.push_str(part);
                }
                l.push('"');
            }
            l.pop();
            l
        } else {
            line.to_owned()
        };
        out.push_str(&scaled);
        out.push('\n');
    }
    out
}

#[test]
fn a_diverging_emulator_fails_the_scenario_instead_of_passing() {
    use super::{run_scenario, Clock};
    let dir = tempfile::tempdir().unwrap();
    // Links 1e30 times too light: the motors' torques accelerate them past f32, and the
    // physics turns NaN (which the wire would carry as zeros: "at rest at 0°").
    std::fs::write(dir.path().join("feather.urdf"), lighter_piper(1e30)).unwrap();
    let path = dir.path().join("feather.yaml");
    let text = "bench:\n  devices:\n    arm: {kind: piper, urdf: feather.urdf}\nsteps:\n  - enable\n  - move_j: {joints_deg: [10, 0, 0, 0, 0, 0], speed_pct: 30}\n  - wait_ms: 300\n  - expect: {joints_max_deg: [1000, 1000, 1000, 1000, 1000, 1000]}\n";
    let scenario = parse_scenario(&path, text).unwrap_or_else(|e| panic!("{e}"));
    let result = run_scenario(&scenario, &Clock::Virtual);
    let Verdict::Error(message) = &result.verdict else {
        panic!("{:?}: {:#?}", result.verdict, result.steps);
    };
    assert!(
        message.starts_with("emulator error: device `arm`: "),
        "{message}"
    );
    assert!(message.contains("physics diverged"), "{message}");
    let failed = result.first_failure().expect("a failed step");
    assert!(
        matches!(&failed.outcome, Outcome::Failed { expected, .. } if expected == "a sound emulator"),
        "{failed:?}"
    );
    // The same bench with the real masses passes.
    std::fs::write(dir.path().join("feather.urdf"), lighter_piper(1.0)).unwrap();
    let scenario = parse_scenario(&path, text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        run_scenario(&scenario, &Clock::Virtual).verdict,
        Verdict::Passed
    );
}

#[test]
fn devices_on_named_buses_get_a_bus_each() {
    let s = parse(
        "bench:\n  devices:\n    left: {kind: piper, bus: can0}\n    right: {kind: piper, bus: can1}\nsteps:\n  - inject: {fault: {drop: {}}, bus: can1, duration_ms: 10}\n",
    );
    let names: Vec<&str> = s.bench.buses.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["can0", "can1"]);
    assert_eq!(s.bench.devices[0].buses, [0]);
    assert_eq!(s.bench.devices[1].buses, [1]);
    let StepKind::Inject { fault, .. } = &s.steps[0].kind else {
        panic!("inject expected");
    };
    assert!(matches!(fault, FaultSpec::Bus { bus: 1, .. }));
    // One bus and no names: the default bus, as before.
    assert_eq!(
        parse(&format!("{BENCH}steps:\n  - estop\n")).bench.buses[0].name,
        DEFAULT_BUS
    );
}

#[test]
fn bus_names_are_checked_where_they_are_written() {
    assert_eq!(
        error(
            "bench:\n  buses: {can0: {}, can1: {bitrate_bps: 500000}}\n  devices:\n    left: {kind: piper, bus: can2}\nsteps:\n  - estop\n"
        ),
        "broken.yaml:4:30: device `left`: no bus `can2` in `bench.buses` (can0, can1); did you mean `can0`?"
    );
    assert_eq!(
        error(
            "bench:\n  buses: {can0: {}, can1: {}}\n  devices:\n    left: {kind: piper}\nsteps:\n  - estop\n"
        ),
        "broken.yaml:4:11: device `left`: the bench has buses can0, can1; say which it is on with `bus:`"
    );
    assert_eq!(
        error(
            "bench:\n  devices:\n    left: {kind: piper, bus: can0}\n    right: {kind: piper, bus: can1}\nsteps:\n  - inject: {fault: {drop: {}}, duration_ms: 10, device: left}\n"
        ),
        "broken.yaml:6:58: bus faults act on the bus, not on a device: select frames with `id:` or `node:` instead of `device:`"
    );
    assert_eq!(
        error(
            "bench:\n  devices:\n    left: {kind: piper, bus: can0}\n    right: {kind: piper, bus: can1}\nsteps:\n  - inject: {fault: {drop: {}}, duration_ms: 10}\n"
        ),
        "broken.yaml:6:5: the bench has buses can0, can1; say which this fault acts on with `bus:`"
    );
    assert_eq!(
        error("bench:\n  devices:\n    left: {kind: piper, bus: 'can 0'}\nsteps:\n  - estop\n"),
        "broken.yaml:3:30: bus name `can 0`: 1 to 15 letters, digits, `_`, `-` or `.` (an interface name)"
    );
}
