//! The four control modes and the special commands, tick by tick on the built-in rig.

use sim::actuator::ActuatorFirmware;
use sim::damiao::codec::{MitCommand, PosForceCommand, PosVelCommand, Special};
use sim::damiao::{DamiaoMotor, Model, MotorConfig};

use super::{answer, decode, mit, motor, one, refresh, run, set_mode, special, std_frame};

#[test]
fn enabled_under_mit_the_motor_holds_against_a_push_like_a_spring() {
    let mut m = motor(0x01, Model::DM4310);
    assert_eq!(refresh(&mut m).state, 0);
    assert_eq!(special(&mut m, Special::Enable).state, 1);
    let start = m.angle_rad();
    let (kp, push) = (40.0, 2.0);
    let hold = MitCommand {
        p_des_rad: start,
        kp_nm_per_rad: kp,
        kd_nm_s_per_rad: 1.0,
        ..MitCommand::default()
    };
    let reply = one(mit(&mut m, hold));
    let reply = decode(&m, reply);
    assert_eq!(reply.state, 1);
    m.set_external_torque(push);
    run(&mut m, 1500);
    // Settled where the spring balances the push: deflection push / kp, torque −push.
    let deflection = m.angle_rad() - start;
    assert!(
        (deflection - push / kp).abs() < 0.004,
        "deflection {deflection}"
    );
    assert!(
        (m.torque_nm() + push).abs() < 0.05,
        "torque {}",
        m.torque_nm()
    );
    assert!(m.speed_rad_s().abs() < 0.01);
    // The feedback carries the same torque (within a 12-bit step over ±10 N·m).
    let fb = refresh(&mut m);
    assert!((fb.torque_nm + push).abs() < 0.06, "{fb:?}");
    assert!((fb.position_rad - m.angle_rad()).abs() < 0.001);
    // Disabled, it applies nothing: the push spins the shaft up.
    assert_eq!(special(&mut m, Special::Disable).state, 0);
    run(&mut m, 200);
    assert_eq!(m.torque_nm(), 0.0);
    assert!(m.speed_rad_s() > 10.0, "speed {}", m.speed_rad_s());
}

#[test]
fn the_mit_torque_is_clamped_to_the_model_s_peak() {
    let mut m = motor(0x01, Model::DM4310);
    special(&mut m, Special::Enable);
    // t_ff at TMAX (10 N·m) on a motor that peaks at 7; held still by an opposing push.
    m.set_external_torque(-20.0);
    one(mit(
        &mut m,
        MitCommand {
            t_ff_nm: 10.0,
            ..MitCommand::default()
        },
    ));
    run(&mut m, 10);
    let peak = Model::DM4310.spec().peak_torque_nm;
    assert!((m.torque_nm() - peak).abs() < 1e-9, "{}", m.torque_nm());
}

#[test]
fn position_velocity_reaches_its_target_within_the_speed_limit() {
    let mut m = motor(0x01, Model::DM4310);
    set_mode(&mut m, 2);
    special(&mut m, Special::Enable);
    let (target, limit) = (1.5f32, 2.0f32);
    let command = PosVelCommand {
        p_des_rad: target,
        v_des_rad_s: limit,
    };
    let fb = answer(&mut m, std_frame(0x101, &command.payload()));
    assert_eq!(fb.state, 1);
    let mut top = 0.0f64;
    for _ in 0..2000 {
        run(&mut m, 1);
        top = top.max(m.speed_rad_s().abs());
    }
    let error = m.angle_rad() - f64::from(target);
    assert!(error.abs() < 0.005, "error {error}");
    assert!(top <= 1.05 * f64::from(limit), "top speed {top}");
    assert!(
        top >= 0.95 * f64::from(limit),
        "never cruised: top speed {top}"
    );
    assert!(m.speed_rad_s().abs() < 0.01);
}

#[test]
fn velocity_mode_takes_dlc_4_and_dlc_8() {
    let mut m = motor(0x01, Model::DM4310);
    set_mode(&mut m, 3);
    special(&mut m, Special::Enable);
    // openarm_can: DLC 4.
    let fb = answer(&mut m, std_frame(0x201, &5.0f32.to_le_bytes()));
    assert_eq!(fb.state, 1);
    run(&mut m, 600);
    assert!((m.speed_rad_s() - 5.0).abs() < 0.05, "{}", m.speed_rad_s());
    // damiao-motor: DLC 8, zero padded.
    let mut padded = [0u8; 8];
    padded[..4].copy_from_slice(&(-2.5f32).to_le_bytes());
    one(m.handle_frame(&std_frame(0x201, &padded)));
    run(&mut m, 600);
    assert!((m.speed_rad_s() + 2.5).abs() < 0.05, "{}", m.speed_rad_s());
    // Past MAX_SPD (the model's 20.9 rad/s): held at MAX_SPD.
    one(m.handle_frame(&std_frame(0x201, &100.0f32.to_le_bytes())));
    run(&mut m, 3000);
    let max = Model::DM4310.spec().max_speed_rad_s;
    assert!(
        m.speed_rad_s() <= max + 0.1 && m.speed_rad_s() > max - 0.5,
        "{}",
        m.speed_rad_s()
    );
}

#[test]
fn force_position_pushes_no_harder_than_its_current_limit() {
    // Some friction, so that giving way settles at a crawl instead of spinning up.
    let config = MotorConfig {
        friction_nm_s_per_rad: 0.5,
        ..MotorConfig::new(0x01, Model::DM4310)
    };
    let mut m = DamiaoMotor::new(config);
    set_mode(&mut m, 4);
    special(&mut m, Special::Enable);
    let command = PosForceCommand {
        p_des_rad: 1.0,
        v_des_rad_s: 5.0,
        current_fraction: 0.2,
    };
    let limit = 0.2 * Model::DM4310.spec().peak_torque_nm;
    // An opposing push larger than the limit: the motor gives way at exactly its limit.
    m.set_external_torque(-3.0);
    one(m.handle_frame(&std_frame(0x301, &command.payload())));
    let mut strongest = 0.0f64;
    for _ in 0..500 {
        run(&mut m, 1);
        strongest = strongest.max(m.torque_nm().abs());
    }
    assert!(strongest <= limit + 1e-9, "{strongest} > {limit}");
    assert!((m.torque_nm() - limit).abs() < 1e-6, "{}", m.torque_nm());
    assert!(m.angle_rad() < 0.0, "pushed back: {}", m.angle_rad());
    // Without the push it reaches the target.
    m.set_external_torque(0.0);
    run(&mut m, 3000);
    assert!((m.angle_rad() - 1.0).abs() < 0.01, "{}", m.angle_rad());
}

#[test]
fn a_command_for_another_mode_is_ignored_without_a_reply() {
    let mut m = motor(0x01, Model::DM4310);
    special(&mut m, Special::Enable);
    let pos_vel = PosVelCommand {
        p_des_rad: 1.0,
        v_des_rad_s: 5.0,
    };
    // MIT is in force: pos-vel, velocity and force-position frames get nothing.
    assert!(m
        .handle_frame(&std_frame(0x101, &pos_vel.payload()))
        .is_empty());
    assert!(m
        .handle_frame(&std_frame(0x201, &3.0f32.to_le_bytes()))
        .is_empty());
    let force = PosForceCommand {
        p_des_rad: 1.0,
        v_des_rad_s: 5.0,
        current_fraction: 1.0,
    };
    assert!(m
        .handle_frame(&std_frame(0x301, &force.payload()))
        .is_empty());
    run(&mut m, 300);
    assert!(m.angle_rad().abs() < 1e-9, "moved to {}", m.angle_rad());
    // In pos-vel mode an MIT setpoint is ignored, but the specials on ESC_ID still work.
    set_mode(&mut m, 2);
    let setpoint = MitCommand {
        p_des_rad: 1.0,
        kp_nm_per_rad: 50.0,
        ..MitCommand::default()
    };
    assert!(mit(&mut m, setpoint).is_empty());
    run(&mut m, 300);
    assert!(m.angle_rad().abs() < 1e-6, "moved to {}", m.angle_rad());
    assert_eq!(special(&mut m, Special::Disable).state, 0);
}

#[test]
fn set_zero_is_taken_while_disabled_only_and_kept_in_flash() {
    let mut m = motor(0x01, Model::DM4310);
    m.set_external_torque(0.05);
    run(&mut m, 300);
    m.set_external_torque(0.0);
    let moved = m.angle_rad();
    assert!(moved > 0.1, "{moved}");
    let fb = special(&mut m, Special::SetZero);
    assert!(fb.position_rad.abs() < 0.001, "{fb:?}");
    assert!(m.angle_rad().abs() < 1e-9);
    assert!(m.take_persist_request());
    assert!(m.persisted()["zero_offset_rad"].as_f64().unwrap() > 0.1);
    // Enabled: answered, ignored.
    special(&mut m, Special::Enable);
    one(mit(
        &mut m,
        MitCommand {
            v_des_rad_s: 2.0,
            kd_nm_s_per_rad: 1.0,
            ..MitCommand::default()
        },
    ));
    run(&mut m, 300);
    let before = m.angle_rad();
    assert!(before > 0.1);
    let fb = special(&mut m, Special::SetZero);
    assert!((fb.position_rad - before).abs() < 0.01, "{fb:?}");
    assert!(!m.take_persist_request());
}

#[test]
fn enabling_never_jumps_toward_a_stale_target() {
    let mut m = motor(0x01, Model::DM4310);
    set_mode(&mut m, 2);
    // A target sent while disabled is answered (state 0) …
    let command = PosVelCommand {
        p_des_rad: 2.0,
        v_des_rad_s: 5.0,
    };
    let fb = answer(&mut m, std_frame(0x101, &command.payload()));
    assert_eq!(fb.state, 0);
    // … but enabling holds where the joint is.
    special(&mut m, Special::Enable);
    run(&mut m, 500);
    assert!(m.angle_rad().abs() < 1e-3, "{}", m.angle_rad());
}

#[test]
fn the_snapshot_speaks_the_contract_s_words() {
    let mut m = motor(0x03, Model::DM4340);
    set_mode(&mut m, 3);
    special(&mut m, Special::Enable);
    let snapshot = m.snapshot();
    assert_eq!(snapshot.kind, "damiao");
    assert_eq!(snapshot.model, "DM4340");
    assert_eq!(snapshot.can_id, 3);
    assert!(snapshot.enabled);
    assert_eq!(snapshot.mode, "velocity");
    assert!(snapshot.faults.is_empty());
    assert!(m.is_running() && !m.sends_nothing_on_its_own());
    assert_eq!(m.kind(), "damiao");
    assert!(m.turnaround() > std::time::Duration::ZERO);
    assert_eq!(m.max_external_torque_nm(), 270.0);
}

#[test]
fn one_substep_per_tick_still_holds_a_position() {
    // A robot's world steps once per tick: the loops must stay stable at 1 kHz.
    let mut m = motor(0x02, Model::DM8009);
    m.set_control_substeps(1);
    set_mode(&mut m, 2);
    special(&mut m, Special::Enable);
    let command = PosVelCommand {
        p_des_rad: -1.0,
        v_des_rad_s: 3.0,
    };
    one(m.handle_frame(&std_frame(0x102, &command.payload())));
    run(&mut m, 2000);
    assert!((m.angle_rad() + 1.0).abs() < 0.005, "{}", m.angle_rad());
}
