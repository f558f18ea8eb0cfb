use std::path::Path;

use crate::devices::robstride::model::{MotorCheck, MotorCond, RsCommand};
use crate::harness::model::{Check, DeviceKind, StepKind};
use crate::harness::parse_scenario;
use crate::harness::test_support::error_of;

const BENCH: &str = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS03, load: {pendulum: {mass_kg: 1.0, length_m: 0.3}}}, {id: 2, model: RS00}]}\n";

#[test]
fn a_valid_bench_step_and_condition_are_typed() {
    let text = format!(
        "{BENCH}steps:\n  - robstride: {{motor: 2, do: velocity, speed_rad_s: 5, limit_cur_a: 10, acc_rad_s2: 20}}\n  - wait_until: {{motors: {{2: {{velocity_rad_s: 5.0, faults: [stall_overload, under_voltage]}}}}, timeout_ms: 100}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let DeviceKind::Robstride(settings) = &s.bench.devices[0].kind else {
        panic!("not a robstride device");
    };
    assert_eq!(settings.motors.len(), 2);
    assert_eq!(
        settings.motors[0].load,
        sim::robstride::Load::Pendulum {
            mass_kg: 1.0,
            length_m: 0.3
        }
    );
    assert_eq!(s.steps[0].label, "robstride velocity");
    let StepKind::Action {
        action: crate::devices::Action::Robstride(a),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a robstride action");
    };
    assert_eq!(a.motor, 2);
    assert!(matches!(a.command, RsCommand::Velocity { speed_rad_s, .. } if speed_rad_s == 5.0));
    let StepKind::WaitUntil { checks, .. } = &s.steps[1].kind else {
        panic!("not wait_until");
    };
    // Flags come back in bit order whatever order the file lists them in.
    assert!(checks.contains(&Check::Robstride(MotorCheck {
        motor: 2,
        cond: MotorCond::StatusFaults(vec!["under_voltage", "stall_overload"])
    })));
}

#[test]
fn absurd_load_parameters_are_refused_at_their_position() {
    let bench = |load: &str| {
        format!("bench:\n  devices:\n    bus: {{kind: robstride, motors: [{{id: 1, model: RS03, {load}}}]}}\nsteps:\n  - wait_ms: 1\n")
    };
    let e = error_of(&bench("load: {pendulum: {mass_kg: 1e308, length_m: 0.3}}"));
    assert!(
        e.starts_with("broken.yaml:3:85: `mass_kg` must be at most 1000, got 1e308"),
        "{e}"
    );
    let e = error_of(&bench("load: {pendulum: {mass_kg: 1.0, length_m: 1e308}}"));
    assert!(e.contains("`length_m` must be at most 10"), "{e}");
    let e = error_of(&bench("load: {disc: {mass_kg: 1.0, radius_m: 1e200}}"));
    assert!(e.contains("`radius_m` must be at most 10"), "{e}");
    let e = error_of(&bench("friction_nm_s_per_rad: 1e300"));
    assert!(e.contains("`friction_nm_s_per_rad` must be between"), "{e}");
    let e = error_of(&bench("start_angle_rad: -1e300"));
    assert!(
        e.contains("`start_angle_rad` must be between -100 and 100"),
        "{e}"
    );
}

#[test]
fn absurd_emulator_values_are_refused_at_their_position() {
    let step = |args: &str| format!("{BENCH}steps:\n  - robstride: {{motor: 1, {args}}}\n");
    let e = error_of(&step("do: external_torque, torque_nm: 1e308"));
    assert_eq!(
        e,
        "broken.yaml:5:59: `torque_nm` must be between -1200 and 1200, got 1e308"
    );
    let e = error_of(&step("do: set_temperature, temp_c: 1e308"));
    assert!(
        e.starts_with("broken.yaml:5:56: `temp_c` must be between -40 and 200, got 1e308"),
        "{e}"
    );
    let e = error_of(&step("do: set_bus_voltage, voltage_v: -3"));
    assert!(
        e.contains("`voltage_v` must be between 0 and 120, got -3"),
        "{e}"
    );
    // Numbers the motor holds as f32 must fit one.
    let e = error_of(&step("do: current, iq_a: 1e300"));
    assert!(e.contains("`iq_a` is too large"), "{e}");
    // Plausible values pass.
    let ok = step("do: external_torque, torque_nm: -30.0");
    assert!(parse_scenario(Path::new("ok.yaml"), &ok).is_ok());
}

#[test]
fn mit_commands_and_protocols_are_typed_and_checked() {
    let step = |args: &str| format!("{BENCH}steps:\n  - robstride: {{motor: 1, {args}}}\n");
    let command = |args: &str| {
        let s = parse_scenario(Path::new("ok.yaml"), &step(args)).expect("valid");
        let StepKind::Action {
            action: crate::devices::Action::Robstride(a),
            ..
        } = &s.steps[0].kind
        else {
            panic!("not a robstride action");
        };
        (s.steps[0].label.clone(), a.command.clone())
    };
    assert_eq!(
        command("do: set_protocol, protocol: mit"),
        (
            "robstride set_protocol".to_owned(),
            RsCommand::SetProtocol(driver::robstride::Protocol::Mit)
        )
    );
    assert_eq!(
        command("do: mit_mode, mode: position").1,
        RsCommand::MitMode(driver::robstride::MitMode::Position)
    );
    assert!(matches!(
        command("do: mit_velocity, speed_rad_s: 2, limit_cur_a: 5").1,
        RsCommand::MitVelocity { speed_rad_s, limit_cur_a } if speed_rad_s == 2.0 && limit_cur_a == 5.0
    ));
    assert!(command("do: mit_zero").1.is_mit());
    assert!(!command("do: set_protocol, protocol: private").1.is_mit());
    // A private run mode is not an MIT one, and a protocol must be named.
    let e = error_of(&step("do: mit_mode, mode: csp"));
    assert!(
        e.contains("`mode`") && e.contains("mit, position, velocity"),
        "{e}"
    );
    let e = error_of(&step("do: set_protocol, protocol: ethercat"));
    assert!(e.contains("private, canopen, mit"), "{e}");
    let e = error_of(&step("do: mit_set_protocol"));
    assert!(e.contains("`protocol`"), "{e}");
    let e = error_of(&step("do: mit_position, target_rad: 1.0"));
    assert!(e.contains("`limit_spd_rad_s`"), "{e}");
}

#[test]
fn unknown_model_is_an_error_at_its_position() {
    let text = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS09}]}\nsteps:\n  - wait_ms: 1\n";
    assert!(error_of(text).starts_with(
        "broken.yaml:3:52: `model`: unknown RobStride model `RS09`; expected one of: RS00"
    ));
}

#[test]
fn duplicate_and_out_of_range_motor_ids_are_refused() {
    let text = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS03}, {id: 1, model: RS00}]}\nsteps:\n  - wait_ms: 1\n";
    assert_eq!(error_of(text), "broken.yaml:3:64: duplicate motor id 1");
    let text = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 128, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
    assert_eq!(
        error_of(text),
        "broken.yaml:3:42: `id`: CAN ID 128 out of range, expected 1..=127"
    );
}

#[test]
fn unknown_key_in_a_step_is_rejected() {
    let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: enable, speed: 3}}\n");
    let e = error_of(&text);
    assert!(
        e.starts_with("broken.yaml:5:39: unknown key `speed`"),
        "{e}"
    );
}

#[test]
fn an_argument_of_another_command_names_the_valid_ones() {
    let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: current, speed_rad_s: 3}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:53: `speed_rad_s` does not apply to `do: current`; it takes: iq_a"
    );
}

#[test]
fn missing_arguments_and_unknown_names_are_errors() {
    let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: csp, target_rad: 1}}\n");
    assert_eq!(
        error_of(&text),
        "broken.yaml:5:5: `csp` needs `limit_spd_rad_s`"
    );
    let text =
        format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: read_param, param: loc_kq}}\n");
    assert!(error_of(&text).starts_with(
        "broken.yaml:5:50: `param`: unknown value `loc_kq`; expected one of: run_mode"
    ));
    let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: inject, fault: melted}}\n");
    assert!(error_of(&text).starts_with("broken.yaml:5:46: `fault`: unknown value `melted`"));
    let text = format!("{BENCH}steps:\n  - robstride: {{do: enable}}\n");
    assert_eq!(error_of(&text), "broken.yaml:5:5: `enable` needs `motor`");
    let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: restart}}\n");
    assert!(error_of(&text).starts_with("broken.yaml:5:24: `do: restart` power-cycles"));
}

#[test]
fn bad_motor_conditions_are_errors() {
    let text = format!("{BENCH}steps:\n  - expect: {{motors: {{1: {{faults: [too_hot]}}}}}}\n");
    assert!(error_of(&text).starts_with(
        "broken.yaml:5:36: `faults`: unknown flag `too_hot`; expected one of: under_voltage"
    ));
    let text = format!("{BENCH}steps:\n  - expect: {{motors: {{1: {{mode_state: running}}}}}}\n");
    assert!(error_of(&text).starts_with("broken.yaml:5:39: `mode_state`: unknown value `running`"));
    let text = format!("{BENCH}steps:\n  - expect: {{motors: {{1: {{velocity: 3}}}}}}\n");
    assert!(error_of(&text).starts_with("broken.yaml:5:27: unknown key `velocity`"));
}

#[test]
fn piper_settings_on_a_robstride_bus_and_motors_on_a_piper_are_refused() {
    let text = "bench:\n  devices:\n    bus: {kind: robstride, firmware: S-V1.8-8, motors: [{id: 1, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
    let e = error_of(text);
    assert!(
        e.starts_with("broken.yaml:3:") && e.contains("`firmware`"),
        "{e}"
    );
    let text = "bench:\n  devices:\n    arm: {kind: piper, motors: [{id: 1, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
    let e = error_of(text);
    assert!(
        e.starts_with("broken.yaml:3:") && e.contains("`motors`"),
        "{e}"
    );
}

#[test]
fn a_step_or_fault_aimed_at_the_wrong_kind_is_refused_at_its_position() {
    let two = "bench:\n  devices:\n    arm: {kind: piper}\n    bus: {kind: robstride, motors: [{id: 1, model: RS03}]}\n";
    let e = error_of(&format!(
        "{two}steps:\n  - move_j: {{device: bus, joints_deg: [0, 0, 0, 0, 0, 0]}}\n"
    ));
    assert!(e.starts_with("broken.yaml:6:"), "{e}");
    assert!(e.contains("device `bus` is a robstride"), "{e}");
    let e = error_of(&format!(
        "{two}steps:\n  - robstride: {{device: arm, motor: 1, do: enable}}\n"
    ));
    assert!(e.contains("device `arm` is a piper"), "{e}");
    let e = error_of(&format!("{two}faults:\n  - {{at_ms: 5, device: arm, fault: {{robstride.stall_overload: {{motor: 1}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert!(e.starts_with("broken.yaml:6:"), "{e}");
    assert!(e.contains("device `arm` is a piper"), "{e}");
}

#[test]
fn a_robstride_fault_is_scheduled_with_its_motor() {
    let text = format!("{BENCH}faults:\n  - {{at_ms: 100, duration_ms: 50, fault: {{under_voltage: {{motor: 2}}}}}}\nsteps:\n  - wait_ms: 1\n");
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    assert_eq!(s.faults.len(), 1);
    assert_eq!(s.faults[0].fault.describe(), "under_voltage motor 2");
    assert_eq!(
        s.faults[0].duration,
        Some(std::time::Duration::from_millis(50))
    );
}

/// One fault builder, three front ends: a scenario file, the web view's page command and the
/// builder itself refuse the same bad arguments with the same message (the scenario's at the
/// argument's line and column).
#[test]
fn scenario_web_view_and_builder_refuse_a_fault_with_one_message() {
    use sim::fault_args::{FaultArgValue, FaultArgs};
    let cases: [(&str, FaultArgs, serde_json::Value, &str); 2] = [
        (
            "{motor: 128}",
            FaultArgs::new().with("motor", FaultArgValue::Number(128.0)),
            serde_json::json!({"motor": 128}),
            "broken.yaml:5:49: ",
        ),
        (
            "{}",
            FaultArgs::new(),
            serde_json::json!({}),
            "broken.yaml:5:",
        ),
    ];
    for (yaml_args, args, json_args, at) in cases {
        let builder = sim::robstride::build_fault("under_voltage", &args)
            .unwrap_err()
            .message;
        let text = format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{under_voltage: {yaml_args}}}}}\nsteps:\n  - wait_ms: 1\n");
        let scenario = error_of(&text);
        assert!(
            scenario.starts_with(at) && scenario.ends_with(&format!(": {builder}")),
            "{scenario} / {builder}"
        );
        let page = crate::ui::page_fault_args(&json_args.as_object().cloned().unwrap_or_default());
        assert_eq!(
            sim::robstride::build_fault("under_voltage", &page).map_err(|e| e.message),
            Err(builder)
        );
    }
}

/// A fault with a value is read like every other argument: the builder takes it, reports name
/// it with its value, and its refusal (out of range, unknown argument) is shown at the value's
/// line and column.
#[test]
fn a_fault_with_a_value_is_read_and_refused_at_its_value() {
    let text = format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{encoder_glitch: {{motor: 1, counts: -300}}}}}}\nsteps:\n  - wait_ms: 1\n");
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    assert_eq!(
        s.faults[0].fault.describe(),
        "encoder_glitch -300 counts motor 1"
    );
    let far = error_of(&format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{encoder_glitch: {{motor: 1, counts: 9000}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert_eq!(
        far,
        "broken.yaml:5:61: `counts`: encoder counts 9000 out of range, expected -8192..=8192"
    );
    let unknown = error_of(&format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{gate_driver: {{motor: 1, volts: 3}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert_eq!(
        unknown,
        "broken.yaml:5:57: fault `gate_driver` has no argument `volts`; it takes: motor"
    );
    // A step has no room for a value: the message says where it goes.
    let step = error_of(&format!(
        "{BENCH}steps:\n  - robstride: {{motor: 1, do: inject, fault: encoder_glitch}}\n"
    ));
    assert!(
        step.starts_with(
            "broken.yaml:5:46: `encoder_glitch` takes `counts`: schedule it in `faults:`"
        ),
        "{step}"
    );
}
