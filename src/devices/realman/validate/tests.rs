//! Unit tests of the Realman grammar: typed values and errors at their positions.

use std::path::Path;

use sim::realman::RealmanFault;

use crate::devices::realman::model::{RmCommand, RmCond};
use crate::devices::{Action, Check, DeviceKind};
use crate::harness::model::StepKind;
use crate::harness::parse_scenario;
use crate::harness::test_support::error_of;

const BENCH: &str = "bench:\n  devices:\n    arm: {kind: realman, clients: 2}\n";

#[test]
fn a_valid_bench_step_condition_and_fault_are_typed() {
    let text = format!(
        "{BENCH}faults:\n  - {{at_ms: 100, for_ms: 50, fault: {{reply_delay: {{delay_ms: 600}}}}}}\nsteps:\n  - realman: {{do: movej, joints_deg: [10, 20, 30, 40, 50, 60], speed: 30, blend: 20, queue: true, client: 2}}\n  - wait_until: {{joints_deg: [10, 20, 30, 40, 50, 60], arm_state: idle, errors: [collision, beyond_joint_limit], timeout_ms: 100}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let DeviceKind::Realman(settings) = &s.bench.devices[0].kind else {
        panic!("not a realman device");
    };
    assert_eq!((settings.model, settings.clients), ("RM65-B", 2));
    let StepKind::Action {
        action: Action::Realman(a),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a realman action");
    };
    assert_eq!(a.client, 1);
    let RmCommand::MoveJ(j, m) = &a.command else {
        panic!("not movej: {:?}", a.command);
    };
    assert_eq!(j[5], 60.0);
    assert!(m.queue && m.block && m.speed == 30 && m.blend == 20);
    let StepKind::WaitUntil { checks, .. } = &s.steps[1].kind else {
        panic!("not wait_until");
    };
    // Error names come back in table (code) order.
    assert!(checks.contains(&Check::Realman(RmCond::Errors(vec![
        "beyond_joint_limit",
        "collision"
    ]))));
    assert!(s.faults[0]
        .fault
        .describe()
        .starts_with("reply_delay 600 ms ("));
    let crate::harness::model::FaultSpec::Emulator {
        fault: crate::devices::DeviceFault::Realman(f),
        ..
    } = &s.faults[0].fault
    else {
        panic!("not a realman fault");
    };
    assert_eq!(f.0, RealmanFault::ReplyDelay { delay_ms: 600 });
}

#[test]
fn bad_arguments_are_errors_at_their_position() {
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: movej, joints_deg: [1, 2, 3], speed: 30}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:5:") && e.contains("`joints_deg` needs 6"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: movej, joints_deg: [0, 0, 0, 0, 0, 0], speed: 101}}\n"
    ));
    assert!(
        e.contains("`speed`: 101 out of range, expected 1..=100"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: pause, speed: 3}}\n"
    ));
    assert!(e.contains("`speed` does not apply to `do: pause`"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: push, period_ms: 7}}\n"
    ));
    assert!(e.contains("multiple of 5"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: read_joints, client: 5}}\n"
    ));
    assert!(e.contains("`client`: 5 out of range"), "{e}");
    let e = error_of(&format!(
        "{BENCH}faults:\n  - {{at_ms: 5, fault: {{joint_error: {{joint: 3}}}}}}\nsteps:\n  - wait_ms: 1\n"
    ));
    assert!(e.contains("`joint_error` needs `code`"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - expect: {{arm_state: dancing}}\n"
    ));
    assert!(e.contains("`arm_state`: unknown value `dancing`"), "{e}");
}
