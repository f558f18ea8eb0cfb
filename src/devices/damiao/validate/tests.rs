use std::path::Path;

use driver::damiao::{ControlMode, Register, RegisterValue};

use crate::devices::damiao::model::{DmCommand, MotorCheck, MotorCond};
use crate::harness::model::{Check, DeviceKind, StepKind};
use crate::harness::parse_scenario;
use crate::harness::test_support::error_of;

const BENCH: &str = "bench:\n  devices:\n    dm: {kind: damiao, motors: [{id: 1, model: DM4310, load: {pendulum: {mass_kg: 0.5, length_m: 0.2}}}, {id: 2, model: DM8009, feedback_id: 0x22}]}\n";

/// The command of a one-step scenario on [`BENCH`], with its label.
fn command(args: &str) -> (String, DmCommand) {
    let text = format!("{BENCH}steps:\n  - damiao: {{{args}}}\n");
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let StepKind::Action {
        action: crate::devices::Action::Damiao(a),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a damiao action");
    };
    (s.steps[0].label.clone(), a.command.clone())
}

/// The error of a one-step scenario on [`BENCH`].
fn step_error(args: &str) -> String {
    error_of(&format!("{BENCH}steps:\n  - damiao: {{{args}}}\n"))
}

#[test]
fn a_valid_bench_step_and_condition_are_typed() {
    let text = format!(
        "{BENCH}steps:\n  - damiao: {{motor: 2, do: mit, p_rad: 0.5, kp: 20, kd: 1}}\n  - wait_until: {{motors: {{1: {{position_rad: 0.5, state: comm_lost, rotor_temp_c: 25}}}}, timeout_ms: 100}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let DeviceKind::Damiao(settings) = &s.bench.devices[0].kind else {
        panic!("not a damiao device");
    };
    let ids: Vec<(u16, u16)> = settings
        .motors
        .iter()
        .map(|m| (m.esc_id, m.mst_id))
        .collect();
    assert_eq!(ids, [(1, 0x11), (2, 0x22)]);
    assert_eq!(
        settings.motors[0].load,
        sim::robstride::Load::Pendulum {
            mass_kg: 0.5,
            length_m: 0.2
        }
    );
    assert_eq!(settings.motors[1].model, sim::damiao::Model::DM8009);
    assert_eq!(s.steps[0].label, "damiao mit");
    let StepKind::Action {
        action: crate::devices::Action::Damiao(a),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a damiao action");
    };
    assert_eq!(a.motor, 2);
    assert_eq!(
        a.command,
        DmCommand::Mit {
            p_rad: 0.5,
            v_rad_s: 0.0,
            kp: 20.0,
            kd: 1.0,
            t_nm: 0.0
        }
    );
    let StepKind::WaitUntil { checks, .. } = &s.steps[1].kind else {
        panic!("not wait_until");
    };
    // A fault's name reads as the state it latches.
    assert!(checks.contains(&Check::Damiao(MotorCheck {
        motor: 1,
        cond: MotorCond::State("communication_lost")
    })));
    assert_eq!(checks.len(), 3);
}

#[test]
fn every_command_is_typed() {
    assert_eq!(
        command("motor: 1, do: mode, mode: vel"),
        (
            "damiao mode".to_owned(),
            DmCommand::Mode(ControlMode::Velocity)
        )
    );
    assert_eq!(
        command("motor: 1, do: pos_vel, p_rad: 1.5, v_rad_s: 2").1,
        DmCommand::PosVel {
            p_rad: 1.5,
            v_rad_s: 2.0
        }
    );
    assert_eq!(
        command("motor: 1, do: force_pos, p_rad: 1, v_rad_s: 5, i_limit: 0.5").1,
        DmCommand::ForcePos {
            p_rad: 1.0,
            v_rad_s: 5.0,
            i_limit: 0.5
        }
    );
    // Registers by their firmware names, in any case, each value in its wire type.
    assert_eq!(
        command("motor: 1, do: write_register, register: timeout, value: 2000").1,
        DmCommand::WriteRegister {
            register: Register::Timeout,
            value: RegisterValue::U32(2000)
        }
    );
    assert_eq!(
        command("motor: 1, do: write_register, register: KT_Value, value: 0.5").1,
        DmCommand::WriteRegister {
            register: Register::KtValue,
            value: RegisterValue::F32(0.5)
        }
    );
    assert!(matches!(
        command("motor: 1, do: read_register, register: PMAX, expect: 12.5").1,
        DmCommand::ReadRegister { register: Register::Pmax, expect: Some(n) } if n.value == 12.5 && n.tolerance == 0.01
    ));
    assert_eq!(
        command("motor: 2, do: poll, period_ms: 0").1,
        DmCommand::Poll {
            period: std::time::Duration::ZERO
        }
    );
    assert_eq!(command("do: restart").1, DmCommand::Restart);
    assert!(command("do: restart").1.needs_emulator());
    assert!(!command("motor: 1, do: save").1.needs_emulator());
}

#[test]
fn unknown_model_is_an_error_at_its_position_with_the_nearest_name() {
    let text = "bench:\n  devices:\n    dm: {kind: damiao, motors: [{id: 1, model: DM431}]}\nsteps:\n  - wait_ms: 1\n";
    let e = error_of(text);
    assert!(
        e.starts_with(
            "broken.yaml:3:48: `model`: unknown Damiao model `DM431`; expected one of: DM3507, DM4310"
        ),
        "{e}"
    );
    assert!(e.ends_with("; did you mean `DM4310`?"), "{e}");
}

#[test]
fn ids_out_of_range_duplicate_or_clashing_are_refused() {
    let bench = |motors: &str| {
        format!("bench:\n  devices:\n    dm: {{kind: damiao, motors: [{motors}]}}\nsteps:\n  - wait_ms: 1\n")
    };
    assert_eq!(
        error_of(&bench("{id: 1279, model: DM4310}")),
        "broken.yaml:3:38: `id`: ESC_ID 1279 out of range, expected 1..=1278 (0x4FE: the force-position command goes to 0x300 + ESC_ID, below 0x7FF)"
    );
    assert!(error_of(&bench("{id: 0, model: DM4310}")).contains("ESC_ID 0 out of range"));
    assert_eq!(
        error_of(&bench("{id: 1, model: DM4310}, {id: 1, model: DM8009}")),
        "broken.yaml:3:62: duplicate motor id 1"
    );
    let e = error_of(&bench("{id: 1, model: DM4310, feedback_id: 0x7FF}"));
    assert!(
        e.starts_with("broken.yaml:3:69: `feedback_id`: 2047 out of range, expected 0..=2046"),
        "{e}"
    );
    // Motor 2 answers on 0x12 by default: no motor may be commanded there.
    let e = error_of(&bench("{id: 0x12, model: DM4310}, {id: 2, model: DM4310}"));
    assert!(
        e.starts_with("broken.yaml:3:65: motor 2 answers on 0x12 (its default feedback_id, id + 0x10), an identifier motor 18 is commanded on"),
        "{e}"
    );
    // Nor on another's position-velocity identifier (0x100 + ESC_ID).
    let e = error_of(&bench("{id: 1, model: DM4310, feedback_id: 0x101}"));
    assert!(e.contains("an identifier motor 1 is commanded on"), "{e}");
    let e = error_of(&bench(
        "{id: 1, model: DM4310, feedback_id: 0x30}, {id: 2, model: DM4310, feedback_id: 0x30}",
    ));
    assert!(e.contains("motors 1 and 2 both answer on 0x30"), "{e}");
}

#[test]
fn broken_keys_are_refused_with_the_nearest_key() {
    let text = "bench:\n  devices:\n    dm: {kind: damiao, motors: [{id: 1, model: DM4310, feedbak_id: 0x11}]}\nsteps:\n  - wait_ms: 1\n";
    let e = error_of(text);
    assert!(
        e.starts_with("broken.yaml:3:") && e.contains("unknown key `feedbak_id`"),
        "{e}"
    );
    assert!(e.ends_with("did you mean `feedback_id`?"), "{e}");
    let e = step_error("motor: 1, do: mit, p_rads: 1");
    assert!(
        e.starts_with("broken.yaml:5:33: unknown key `p_rads`")
            && e.ends_with("did you mean `p_rad`?"),
        "{e}"
    );
    let e = step_error("motor: 1, do: enabel");
    assert!(
        e.starts_with("broken.yaml:5:28: `do`: unknown value `enabel`; expected one of: enable")
            && e.ends_with("did you mean `enable`?"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - expect: {{motors: {{1: {{state: enabeld}}}}}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:5:34: `state`: unknown value `enabeld`; expected one of: disabled, enabled")
            && e.ends_with("did you mean `enabled`?"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - expect: {{motors: {{1: {{position: 1}}}}}}\n"
    ));
    assert!(
        e.starts_with("broken.yaml:5:27: unknown key `position`"),
        "{e}"
    );
}

#[test]
fn arguments_motors_and_registers_are_checked_at_their_place() {
    assert_eq!(
        step_error("motor: 1, do: vel, kp: 3"),
        "broken.yaml:5:37: `kp` does not apply to `do: vel`; it takes: v_rad_s"
    );
    assert_eq!(
        step_error("motor: 1, do: pos_vel, p_rad: 1"),
        "broken.yaml:5:5: `pos_vel` needs `v_rad_s`"
    );
    assert_eq!(
        step_error("do: enable"),
        "broken.yaml:5:5: `enable` needs `motor`"
    );
    assert_eq!(
        step_error("motor: 3, do: enable"),
        "broken.yaml:5:21: no motor 3 on device `dm`; its motors: 1, 2"
    );
    assert!(step_error("motor: 1, do: restart")
        .starts_with("broken.yaml:5:21: `do: restart` power-cycles"));
    let e = step_error("motor: 1, do: read_register, register: KT_Valu");
    assert!(
        e.starts_with(
            "broken.yaml:5:53: `register`: unknown register `KT_Valu`; expected one of: UV_Value"
        ) && e.ends_with("did you mean `KT_Value`?"),
        "{e}"
    );
    assert_eq!(
        step_error("motor: 1, do: write_register, register: SN, value: 3"),
        "broken.yaml:5:54: `register`: SN (RID 15) is read-only"
    );
    assert!(
        step_error("motor: 1, do: write_register, register: ESC_ID, value: 3")
            .contains("moves the motor to another identifier")
    );
    assert!(
        step_error("motor: 1, do: write_register, register: TIMEOUT, value: 2.5")
            .contains("`value`: TIMEOUT holds a whole number")
    );
    assert!(step_error("motor: 1, do: mit, kp: 1e300").contains("`kp` is too large"));
    let e = step_error("motor: 1, do: mode, mode: velocity");
    assert!(
        e.contains(
            "`mode`: unknown value `velocity`; expected one of: mit, pos_vel, vel, force_pos"
        ),
        "{e}"
    );
    // The push is bounded by the motor's own model: ten times a DM4310's 7 N·m peak.
    assert_eq!(
        step_error("motor: 1, do: external_torque, torque_nm: 100"),
        "broken.yaml:5:56: `torque_nm` must be between -70 and 70, got 100.0"
    );
    assert!(parse_scenario(
        Path::new("ok.yaml"),
        &format!("{BENCH}steps:\n  - damiao: {{motor: 2, do: external_torque, torque_nm: 100}}\n")
    )
    .is_ok());
    assert!(step_error("motor: 1, do: set_temperature, temp_c: 1e308")
        .contains("`temp_c` must be between -40 and 200"));
}

#[test]
fn a_damiao_fault_is_scheduled_with_its_motor_and_checked_by_its_model() {
    let text = format!("{BENCH}faults:\n  - {{at_ms: 100, duration_ms: 50, fault: {{under_voltage: {{motor: 2, voltage_v: 5}}}}}}\nsteps:\n  - wait_ms: 1\n");
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    assert_eq!(
        s.faults[0].fault.describe(),
        "under_voltage voltage_v=5 motor 2"
    );
    // 20 V does not trip a 24 V motor's under-voltage (12 V): refused at the value.
    let e = error_of(&format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{under_voltage: {{motor: 1, voltage_v: 20}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert!(
        e.starts_with(
            "broken.yaml:5:63: `voltage_v`: 20 V does not trip under_voltage; expected 0..=12"
        ),
        "{e}"
    );
    let e = error_of(&format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{overload: {{motor: 4}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert!(
        e.starts_with("broken.yaml:5:44: no motor 4 on device `dm`"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}faults:\n  - {{at_ms: 100, fault: {{overload: {{}}}}}}\nsteps:\n  - wait_ms: 1\n"
    ));
    assert!(e.contains("`overload` needs `motor`"), "{e}");
    let e = error_of(&format!("{BENCH}faults:\n  - {{at_ms: 100, fault: {{overlaod: {{motor: 1}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert!(
        e.contains("unknown fault `overlaod`") && e.ends_with("did you mean `overload`?"),
        "{e}"
    );
    // A step injects the same faults.
    let text = format!(
        "{BENCH}steps:\n  - inject: {{fault: {{coil_over_temperature: {{motor: 1, temperature_c: 130}}}}}}\n"
    );
    assert!(parse_scenario(Path::new("ok.yaml"), &text).is_ok());
}

#[test]
fn a_step_or_fault_aimed_at_the_wrong_kind_is_refused() {
    let two = "bench:\n  devices:\n    arm: {kind: piper}\n    dm: {kind: damiao, motors: [{id: 1, model: DM4310}]}\n";
    let e = error_of(&format!(
        "{two}steps:\n  - damiao: {{device: arm, motor: 1, do: enable}}\n"
    ));
    assert!(e.contains("device `arm` is a piper"), "{e}");
    let e = error_of(&format!("{two}faults:\n  - {{at_ms: 5, device: arm, fault: {{damiao.overload: {{motor: 1}}}}}}\nsteps:\n  - wait_ms: 1\n"));
    assert!(e.contains("device `arm` is a piper"), "{e}");
    // Without `device:`, the Damiao device that has the motor.
    let text = format!("{two}faults:\n  - {{at_ms: 5, device: dm, fault: {{overload: {{motor: 1}}}}}}\nsteps:\n  - wait_ms: 1\n");
    assert!(parse_scenario(Path::new("ok.yaml"), &text).is_ok());
}

/// RobStride's conditions are `motors:` too: on a bench of both, `damiao.motors` (and
/// `damiao.under_voltage` for a fault both kinds name) picks the Damiao ones.
#[test]
fn beside_a_robstride_bus_the_shared_keys_are_qualified_by_kind() {
    let two = "bench:\n  devices:\n    rs: {kind: robstride, motors: [{id: 1, model: RS03}]}\n    dm: {kind: damiao, motors: [{id: 1, model: DM4310}]}\n";
    let text = format!(
        "{two}faults:\n  - {{at_ms: 5, device: dm, fault: {{damiao.under_voltage: {{motor: 1}}}}}}\nsteps:\n  - expect: {{device: dm, damiao.motors: {{1: {{state: enabled}}}}}}\n  - expect: {{device: rs, motors: {{1: {{mode_state: run}}}}}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let StepKind::Expect { checks, .. } = &s.steps[0].kind else {
        panic!("not an expect");
    };
    assert_eq!(
        checks[0],
        Check::Damiao(MotorCheck {
            motor: 1,
            cond: MotorCond::State("enabled")
        })
    );
    let StepKind::Expect { checks, .. } = &s.steps[1].kind else {
        panic!("not an expect");
    };
    assert_eq!(checks[0].kind_name(), "robstride");
    assert_eq!(s.faults[0].fault.describe(), "under_voltage motor 1");
    // Unqualified, `motors` is the first kind's on the bench: RobStride's, which has no `state`.
    let e = error_of(&format!(
        "{two}steps:\n  - expect: {{device: dm, motors: {{1: {{state: enabled}}}}}}\n"
    ));
    assert!(e.contains("unknown key `state`"), "{e}");
}
