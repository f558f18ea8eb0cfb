//! Unit tests of the Realman grammar: typed values and errors at their positions.

use std::path::Path;

use serde_json::{json, Map, Value};
use sim::fault_args::{FaultArgValue, FaultArgs};
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

/// The command of the only step of `steps` (YAML lines after `steps:`).
fn command_of(steps: &str) -> RmCommand {
    let text = format!("{BENCH}steps:\n{steps}");
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let StepKind::Action {
        action: Action::Realman(a),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a realman action");
    };
    a.command.clone()
}

#[test]
fn streams_jogs_and_parameters_are_typed() {
    use crate::devices::realman::model::{
        JogAxis, JogTarget, Param, Stream, StreamMode, StreamPath,
    };
    let c = command_of("  - realman: {do: stream_joints, from_deg: [0, 0, 0, 0, 0, 0], to_deg: [6, 5, 4, 3, 2, 1], duration_ms: 500, mode: follow, block: false}\n");
    let RmCommand::Stream(Stream {
        path: StreamPath::Joints { to_deg, .. },
        duration_ms: 500,
        period_ms: 10,
        mode: StreamMode::Follow,
        block: false,
    }) = &c
    else {
        panic!("not the stream: {c:?}");
    };
    assert_eq!(to_deg[0], 6.0);
    assert_eq!(c.name(), "stream_joints");
    let c = command_of("  - realman: {do: set_pos_step, axis: z, step_m: -0.05, speed: 40}\n");
    assert_eq!(
        c,
        RmCommand::Step {
            target: JogTarget::Position(JogAxis::Z),
            amount: -0.05,
            speed: 40,
            block: true
        }
    );
    let c = command_of("  - realman: {do: set_joint_teach, joint: 3, direction: neg}\n");
    assert_eq!(
        c,
        RmCommand::Teach {
            target: JogTarget::Joint(3),
            positive: false,
            speed: 20
        }
    );
    let c = command_of("  - realman: {do: get_param, name: dh_d_m, joint: 6, expect: 0.144}\n");
    let RmCommand::GetParam {
        param: Param::DhD,
        joint: Some(6),
        expect: Some(e),
    } = c
    else {
        panic!("not get_param: {c:?}");
    };
    assert_eq!((e.value, e.tolerance), (0.144, 0.001));
}

#[test]
fn bad_new_commands_are_errors_at_their_line() {
    let e = error_of(&format!(
        "{BENCH}steps:\n  - wait_ms: 1\n  - realman: {{do: stream_joints, from_deg: [0, 0, 0, 0, 0, 0], to_deg: [1, 2, 3], duration_ms: 100}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:6:") && e.contains("`to_deg` needs 6"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: stream_joints, from_deg: [0, 0, 0, 0, 0, 0], to_deg: [0, 0, 0, 0, 0, 0], duration_ms: 100, period_ms: 200}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:5:") && e.contains("longer than `duration_ms` 100"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: stream_pose, position_m: [0, 0, 0.3], euler_deg: [180, 0, 0], duration_ms: 100}}\n"
    ));
    assert!(e.contains("`stream_pose` needs `from_position_m`"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: stream_joints, from_deg: [0, 0, 0, 0, 0, 0], to_deg: [0, 0, 0, 0, 0, 0], duration_ms: 100, mode: fast}}\n"
    ));
    assert!(e.contains("`mode`: unknown value `fast`"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: set_joint_teach, joint: 2, direction: up}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:5:") && e.contains("expected one of: pos, neg"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: set_pos_step, axis: x, step_deg: 3}}\n"
    ));
    assert!(
        e.contains("`step_deg` does not apply to `do: set_pos_step`"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: set_joint_step, joint: 8, step_deg: 3}}\n"
    ));
    assert!(e.contains("`joint`: 8 out of range"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: set_param, name: joint_max_speed_deg_s, value: 45}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:5:") && e.contains("say which with `joint:`"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: get_param, name: max_line_speed}}\n"
    ));
    assert!(
        e.contains("`name`: unknown value `max_line_speed`; expected one of: max_line_speed_m_s"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: set_param, name: self_collision, value: 2}}\n"
    ));
    assert!(e.contains("`self_collision` takes 0 or 1"), "{e}");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - realman: {{do: set_param, name: collision_stage, joint: 1, value: 2}}\n"
    ));
    assert!(e.contains("is not per joint"), "{e}");
}

/// The headline of the error a fault entry `fault` (flow YAML) gets: `(line:col, message)`.
fn fault_error(fault: &str) -> (String, String) {
    let headline = error_of(&format!(
        "{BENCH}faults:\n  - {{at_ms: 5, fault: {fault}}}\nsteps:\n  - wait_ms: 1\n"
    ));
    // `broken.yaml:LINE:COL: message`
    let mut parts = headline.splitn(4, ':');
    let _file = parts.next();
    let place = format!(
        "{}:{}",
        parts.next().unwrap_or(""),
        parts.next().unwrap_or("")
    );
    (place, parts.next().unwrap_or_default().trim().to_owned())
}

fn number(name: &str, value: f64) -> FaultArgs {
    FaultArgs::new().with(name, FaultArgValue::Number(value))
}

#[test]
fn scenario_web_view_and_builder_refuse_bad_arguments_alike() {
    let cases = [
        (
            "{reply_delay: {delay_ms: -5}}",
            "reply_delay",
            json!({"delay_ms": -5}),
            number("delay_ms", -5.0),
        ),
        (
            "{udp_loss: {permille: 1001}}",
            "udp_loss",
            json!({"permille": 1001}),
            number("permille", 1001.0),
        ),
        (
            "{joint_error: {joint: 3}}",
            "joint_error",
            json!({"joint": 3}),
            number("joint", 3.0),
        ),
        (
            "{joint_error: {joint: 8, code: 8}}",
            "joint_error",
            json!({"joint": 8, "code": 8}),
            number("joint", 8.0).with("code", FaultArgValue::Number(8.0)),
        ),
        (
            "{estop: {bits: 1}}",
            "estop",
            json!({"bits": 1}),
            number("bits", 1.0),
        ),
        (
            "{reply_delay: {delay_ms: 600, count: 2}}",
            "reply_delay",
            json!({"delay_ms": 600, "count": 2}),
            number("delay_ms", 600.0).with("count", FaultArgValue::Number(2.0)),
        ),
    ];
    for (yaml, name, page, args) in cases {
        let built = sim::realman::build_fault(name, &args).unwrap_err().message;
        assert_eq!(fault_error(yaml).1, built, "{yaml}");
        let page = page
            .as_object()
            .cloned()
            .unwrap_or_else(Map::<String, Value>::new);
        let web = sim::realman::build_fault(name, &crate::ui::page_fault_args(&page))
            .unwrap_err()
            .message;
        assert_eq!(web, built, "{yaml}");
    }
    // The scenario error points at the refused argument, or at the fault when one is missing.
    let line = 5;
    let value_col = "  - {at_ms: 5, fault: {reply_delay: {delay_ms: ".len() + 1;
    assert_eq!(
        fault_error("{reply_delay: {delay_ms: -5}}").0,
        format!("{line}:{value_col}")
    );
    let fault_col = "  - {at_ms: 5, fault: ".len() + 1;
    assert_eq!(
        fault_error("{joint_error: {joint: 3}}").0,
        format!("{line}:{fault_col}")
    );
}
