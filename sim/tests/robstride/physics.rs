//! The emulated actuators against the rig's physics: run modes behave as the manual says and
//! the feedback reports what the motor really does.

use bus::CanFrame;
use sim::robstride::rig::GRAVITY_M_S2;
use sim::robstride::{Actuator, Fault, Load, ModeState, Model, MotorConfig};

const MOTOR: u8 = 0x01;

fn write_f32(motor: &mut Actuator, index: u16, value: f32) {
    let [lo, hi] = index.to_le_bytes();
    let v = value.to_le_bytes();
    let frame = CanFrame::extended(0x1200_FD01, &[lo, hi, 0, 0, v[0], v[1], v[2], v[3]]).unwrap();
    assert_eq!(motor.handle_frame(&frame).len(), 1);
}

fn write_u8(motor: &mut Actuator, index: u16, value: u8) {
    let [lo, hi] = index.to_le_bytes();
    let frame = CanFrame::extended(0x1200_FD01, &[lo, hi, 0, 0, value, 0, 0, 0]).unwrap();
    assert_eq!(motor.handle_frame(&frame).len(), 1);
}

fn write_u32(motor: &mut Actuator, index: u16, value: u32) {
    let [lo, hi] = index.to_le_bytes();
    let v = value.to_le_bytes();
    let frame = CanFrame::extended(0x1200_FD01, &[lo, hi, 0, 0, v[0], v[1], v[2], v[3]]).unwrap();
    assert_eq!(motor.handle_frame(&frame).len(), 1);
}

fn enable(motor: &mut Actuator) {
    let frame = CanFrame::extended(0x0300_FD01, &[0; 8]).unwrap();
    motor.handle_frame(&frame);
    assert_eq!(motor.snapshot().mode, ModeState::Run);
}

/// Poll with an (undocumented) host type-2 frame and decode the torque of the reply, the way a
/// host would see it (manual scaling, RS03 ±60 N·m).
fn reported_torque_rs03(motor: &mut Actuator) -> f64 {
    let poll = CanFrame::extended(0x0200_FD01, &[0; 8]).unwrap();
    let reply = motor.handle_frame(&poll)[0];
    let raw = u16::from_be_bytes([reply.data()[4], reply.data()[5]]);
    f64::from(raw) * 120.0 / 65535.0 - 60.0
}

fn disc_motor(model: Model) -> Actuator {
    let config = MotorConfig::new(MOTOR, model).with_load(Load::Disc {
        mass_kg: 2.0,
        radius_m: 0.1,
    });
    Actuator::new(config, None, 1_000_000)
}

fn run_ms(motor: &mut Actuator, ms: u32) {
    for _ in 0..ms {
        motor.tick();
    }
}

#[test]
fn velocity_mode_ramps_with_acc_rad_to_spd_ref() {
    let mut rs03 = disc_motor(Model::RS03);
    write_u8(&mut rs03, 0x7005, 2);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7018, 20.0); // limit_cur
    write_f32(&mut rs03, 0x7022, 8.0); // acc_rad
    write_f32(&mut rs03, 0x700A, 10.0); // spd_ref
    let (mut t_low, mut t_high) = (None, None);
    for ms in 1..=3000u32 {
        rs03.tick();
        let speed = rs03.snapshot().speed_rad_s;
        if t_low.is_none() && speed >= 2.0 {
            t_low = Some(ms);
        }
        if t_high.is_none() && speed >= 8.0 {
            t_high = Some(ms);
        }
    }
    let (t_low, t_high) = (t_low.unwrap(), t_high.unwrap());
    let acceleration = 6.0 / (f64::from(t_high - t_low) * 1e-3);
    assert!(
        (acceleration - 8.0).abs() <= 0.4,
        "acceleration {acceleration}"
    );
    let final_speed = rs03.snapshot().speed_rad_s;
    assert!((final_speed - 10.0).abs() <= 0.5, "speed {final_speed}");
}

#[test]
fn current_mode_torque_is_iq_times_the_torque_constant() {
    let mut rs03 = disc_motor(Model::RS03);
    write_u8(&mut rs03, 0x7005, 3);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7006, 2.0); // iq_ref
    run_ms(&mut rs03, 10);
    let v0 = rs03.snapshot().speed_rad_s;
    // 30 ms: the disc reaches ~18 rad/s, where the torque–speed line still allows 8 N·m.
    run_ms(&mut rs03, 30);
    let v1 = rs03.snapshot().speed_rad_s;
    let kt = Model::RS03.spec().torque_constant_nm_per_a;
    let expected = 2.0 * kt;
    // The plant's inertia: disc ½·m·r² plus the rotor.
    let inertia = 0.5 * 2.0 * 0.01 + Model::RS03.spec().rotor_inertia_kg_m2;
    let produced = inertia * (v1 - v0) / 0.03;
    assert!(
        (produced - expected).abs() <= 0.05 * expected,
        "{produced} vs {expected}"
    );
    let reported = reported_torque_rs03(&mut rs03);
    assert!((reported - expected).abs() <= 0.05 * expected, "{reported}");
}

#[test]
fn pendulum_held_at_90_degrees_in_csp_needs_mgl() {
    let (mass, length) = (1.5, 0.4);
    let config = MotorConfig::new(MOTOR, Model::RS03).with_load(Load::Pendulum {
        mass_kg: mass,
        length_m: length,
    });
    let mut rs03 = Actuator::new(config, None, 1_000_000);
    write_u8(&mut rs03, 0x7005, 5);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7017, 2.0); // limit_spd
    write_f32(&mut rs03, 0x7016, std::f32::consts::FRAC_PI_2); // loc_ref
                                                               // The climb at 2 rad/s takes under a second; the speed loop's integral settles after.
    run_ms(&mut rs03, 6000);
    let snap = rs03.snapshot();
    assert!(
        (snap.angle_rad - std::f64::consts::FRAC_PI_2).abs() < 0.01,
        "{}",
        snap.angle_rad
    );
    let mgl = mass * GRAVITY_M_S2 * length;
    assert!(
        (snap.torque_nm - mgl).abs() <= 0.05 * mgl,
        "{} vs {mgl}",
        snap.torque_nm
    );
    let reported = reported_torque_rs03(&mut rs03);
    assert!(
        (reported - mgl).abs() <= 0.05 * mgl,
        "reported {reported} vs {mgl}"
    );
}

#[test]
fn csp_respects_limit_spd() {
    let mut rs03 = disc_motor(Model::RS03);
    write_u8(&mut rs03, 0x7005, 5);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7017, 1.5);
    write_f32(&mut rs03, 0x7016, 3.0);
    let mut peak: f64 = 0.0;
    for _ in 0..4000 {
        rs03.tick();
        peak = peak.max(rs03.snapshot().speed_rad_s);
    }
    assert!((1.5 * 0.95..=1.5 * 1.05).contains(&peak), "peak {peak}");
    assert!((rs03.snapshot().angle_rad - 3.0).abs() < 0.01);
}

#[test]
fn pp_moves_with_the_profile_speed_and_stops_at_the_target() {
    let mut rs00 = disc_motor(Model::RS00);
    write_u8(&mut rs00, 0x7005, 1);
    enable(&mut rs00);
    write_f32(&mut rs00, 0x7024, 3.0); // vel_max
    write_f32(&mut rs00, 0x7025, 6.0); // acc_set
    write_f32(&mut rs00, 0x7016, 4.0); // loc_ref
    let mut peak: f64 = 0.0;
    for _ in 0..3000 {
        rs00.tick();
        peak = peak.max(rs00.snapshot().speed_rad_s);
    }
    assert!((peak - 3.0).abs() <= 0.15, "peak {peak}");
    let snap = rs00.snapshot();
    assert!((snap.angle_rad - 4.0).abs() < 0.01, "{}", snap.angle_rad);
    assert!(snap.speed_rad_s.abs() < 0.05);
}

#[test]
fn pp_ignores_set_zero_but_csp_accepts_it_without_a_jump() {
    let mut rs00 = disc_motor(Model::RS00);
    write_u8(&mut rs00, 0x7005, 5);
    enable(&mut rs00);
    write_f32(&mut rs00, 0x7016, 1.0);
    run_ms(&mut rs00, 2000);
    let zero = CanFrame::extended(0x0600_FD01, &[1, 0, 0, 0, 0, 0, 0, 0]).unwrap();
    rs00.handle_frame(&zero);
    run_ms(&mut rs00, 500);
    let snap = rs00.snapshot();
    assert!(
        snap.angle_rad.abs() < 0.01,
        "zeroed, held: {}",
        snap.angle_rad
    );

    let mut rs00 = disc_motor(Model::RS00);
    write_u8(&mut rs00, 0x7005, 1);
    enable(&mut rs00);
    write_f32(&mut rs00, 0x7016, 1.0);
    run_ms(&mut rs00, 2000);
    rs00.handle_frame(&zero);
    assert!(
        (rs00.snapshot().angle_rad - 1.0).abs() < 0.01,
        "PP ignores zeroing"
    );
}

#[test]
fn zero_mode_returns_slowly_to_the_mechanical_zero() {
    let mut config = MotorConfig::new(MOTOR, Model::RS03);
    config.start_angle_rad = 2.0;
    let mut rs03 = Actuator::new(config, None, 1_000_000);
    write_u8(&mut rs03, 0x7005, 4);
    enable(&mut rs03);
    let mut peak: f64 = 0.0;
    for _ in 0..4000 {
        rs03.tick();
        peak = peak.max(rs03.snapshot().speed_rad_s.abs());
    }
    assert!(rs03.snapshot().angle_rad.abs() < 0.01);
    assert!(peak <= 1.05, "slow: {peak}");
}

#[test]
fn op_control_torque_is_limited_by_the_model_and_limit_torque() {
    let mut rs00 = disc_motor(Model::RS00);
    enable(&mut rs00);
    // t_ff = +14 N·m (raw 0xFFFF), kp = kd = 0.
    let full = CanFrame::extended(0x01FF_FF01, &[0x7F, 0xFF, 0x7F, 0xFF, 0, 0, 0, 0]).unwrap();
    rs00.handle_frame(&full);
    rs00.tick();
    // 14 N·m is the stall torque; after 1 ms the disc turns at ~1.4 rad/s, where the
    // torque–speed line allows 14·(1 − ω/ω₀).
    let snap = rs00.snapshot();
    let allowed = 14.0 * (1.0 - snap.speed_rad_s / Model::RS00.spec().no_load_speed_rad_s);
    assert!(snap.speed_rad_s > 1.0);
    assert!((snap.torque_nm - allowed).abs() < 0.1, "{snap:?}");
    write_f32(&mut rs00, 0x700B, 5.0); // limit_torque
    rs00.handle_frame(&full);
    rs00.tick();
    assert!((rs00.snapshot().torque_nm - 5.0).abs() < 1e-6);
}

#[test]
fn can_timeout_drops_the_motor_to_reset() {
    let mut rs03 = disc_motor(Model::RS03);
    write_u32(&mut rs03, 0x7028, 10_000); // 0.5 s at 20000 ticks/s
    enable(&mut rs03);
    run_ms(&mut rs03, 450);
    assert_eq!(rs03.snapshot().mode, ModeState::Run);
    // Any frame to the motor feeds the watchdog.
    let poll = CanFrame::extended(0x0200_FD01, &[0; 8]).unwrap();
    rs03.handle_frame(&poll);
    run_ms(&mut rs03, 450);
    assert_eq!(rs03.snapshot().mode, ModeState::Run);
    run_ms(&mut rs03, 100);
    assert_eq!(rs03.snapshot().mode, ModeState::Reset);
}

#[test]
fn heating_raises_the_warning_before_the_fault() {
    let mut config = MotorConfig::new(MOTOR, Model::RS03).with_load(Load::Disc {
        mass_kg: 50.0,
        radius_m: 0.5,
    });
    config.thermal_time_constant_s = 2.0;
    config.overload_time_at_peak_s = 1.0e6;
    let mut rs03 = Actuator::new(config, None, 1_000_000);
    write_u8(&mut rs03, 0x7005, 3);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7006, 30.0);
    // Stalled: the load pushes back with the motor's 60 N·m limit, so the current flows
    // (a free rotor would reach the no-load speed and draw none).
    rs03.set_external_torque(-60.0);
    let mut fault_frames = Vec::new();
    for ms in 0..20_000u32 {
        for frame in rs03.tick() {
            if frame.raw_id() >> 24 == 21 {
                fault_frames.push((ms, frame));
            }
        }
    }
    assert!(fault_frames.len() >= 2, "{fault_frames:?}");
    let word = |frame: &CanFrame| u32::from_le_bytes(frame.data()[0..4].try_into().unwrap());
    let warning = |frame: &CanFrame| u32::from_le_bytes(frame.data()[4..8].try_into().unwrap());
    assert_eq!(
        (word(&fault_frames[0].1), warning(&fault_frames[0].1)),
        (0, 1)
    );
    assert_eq!(
        (word(&fault_frames[1].1), warning(&fault_frames[1].1)),
        (1, 1)
    );
    assert!(fault_frames[0].0 < fault_frames[1].0);
    let snap = rs03.snapshot();
    assert_eq!(snap.mode, ModeState::Reset);
    assert_ne!(snap.fault_word & Fault::OverTemperature.word_bit(), 0);
}

#[test]
fn sustained_overcurrent_trips_the_i2t_overload() {
    let mut config = MotorConfig::new(MOTOR, Model::RS03).with_load(Load::Disc {
        mass_kg: 50.0,
        radius_m: 0.5,
    });
    config.thermal_time_constant_s = 1.0e6;
    let mut rs03 = Actuator::new(config, None, 1_000_000);
    write_u8(&mut rs03, 0x7005, 3);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7006, 25.0);
    // Stalled, as in the heating test.
    rs03.set_external_torque(-25.0 * Model::RS03.spec().torque_constant_nm_per_a);
    let budget = (43.0f64.powi(2) - 13.0f64.powi(2)) * 2.0;
    let expected_s = budget / (25.0f64.powi(2) - 13.0f64.powi(2));
    let mut tripped = None;
    for ms in 0..10_000u32 {
        rs03.tick();
        if rs03.snapshot().fault_word & Fault::StallOverload.word_bit() != 0 {
            tripped = Some(f64::from(ms) * 1e-3);
            break;
        }
    }
    let tripped = tripped.expect("overload trips");
    assert!(
        (tripped - expected_s).abs() < 0.05,
        "{tripped} vs {expected_s}"
    );
}

/// `urdf/robstride_rig.urdf` is the generator's default instance (RS03 driving a 1 kg
/// pendulum of 0.3 m); regenerate with `ARMHIL_BLESS=1`.
#[test]
fn rig_urdf_file_matches_the_generator() {
    use sim::robstride::rig::rig_urdf;
    let ranges = Model::RS03.ranges(Default::default());
    let text = rig_urdf(
        Load::Pendulum {
            mass_kg: 1.0,
            length_m: 0.3,
        },
        f64::from(ranges.torque_nm),
        f64::from(ranges.speed_rad_s),
    );
    let path = format!("{}/../urdf/robstride_rig.urdf", env!("CARGO_MANIFEST_DIR"));
    if std::env::var_os("ARMHIL_BLESS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    let on_disk = std::fs::read_to_string(&path).unwrap();
    assert_eq!(on_disk, text);
    let robot = urdf_rs::read_from_string(&on_disk).expect("valid URDF");
    assert_eq!(robot.joints.len(), 1);
    let load = robot.links.iter().find(|l| l.name == "load").unwrap();
    assert_eq!(load.inertial.mass.value, 1.0);
    assert_eq!(load.inertial.origin.xyz.0, [0.0, 0.0, -0.3]);
}

/// The same CSP hold on the rig's URDF in the rapier world agrees with the analytic rig.
#[test]
fn pendulum_hold_in_the_physics_world_needs_mgl_too() {
    let (mass, length) = (1.0, 0.3);
    let mut config = MotorConfig::new(MOTOR, Model::RS03).with_load(Load::Pendulum {
        mass_kg: mass,
        length_m: length,
    });
    config.plant = sim::robstride::PlantKind::World;
    let mut rs03 = Actuator::new(config, None, 1_000_000);
    write_u8(&mut rs03, 0x7005, 5);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7017, 2.0);
    write_f32(&mut rs03, 0x7016, std::f32::consts::FRAC_PI_2);
    run_ms(&mut rs03, 6000);
    let snap = rs03.snapshot();
    assert!(
        (snap.angle_rad - std::f64::consts::FRAC_PI_2).abs() < 0.01,
        "{}",
        snap.angle_rad
    );
    let mgl = mass * GRAVITY_M_S2 * length;
    assert!(
        (snap.torque_nm - mgl).abs() <= 0.05 * mgl,
        "{} vs {mgl}",
        snap.torque_nm
    );
}

#[test]
fn constant_torque_stops_accelerating_at_the_no_load_speed() {
    for model in [Model::RS03, Model::RS00, Model::RS04] {
        let mut motor = disc_motor(model);
        write_u8(&mut motor, 0x7005, 3);
        enable(&mut motor);
        // Half the peak torque, held constant.
        let kt = model.spec().torque_constant_nm_per_a;
        write_f32(
            &mut motor,
            0x7006,
            (0.5 * model.spec().peak_torque_nm / kt) as f32,
        );
        run_ms(&mut motor, 1500);
        let v1 = motor.snapshot().speed_rad_s;
        run_ms(&mut motor, 200);
        let v2 = motor.snapshot().speed_rad_s;
        let no_load = model.spec().no_load_speed_rad_s;
        eprintln!(
            "{model:?}: plateau {v2:.3} rad/s, model no-load {no_load:.3} rad/s, \
             last 200 ms +{:.4} rad/s, torque {:.3} N·m",
            v2 - v1,
            motor.snapshot().torque_nm
        );
        assert!((v2 - no_load).abs() < 0.01 * no_load, "{model:?}: {v2}");
        assert!(
            (v2 - v1).abs() < 0.002 * no_load,
            "{model:?} still accelerating"
        );
        assert!(v2 <= no_load + 1e-9, "{model:?} beyond the no-load speed");
    }
}

/// Spin the disc to 10 rad/s in velocity mode, then stop the motor (type 4).
fn spin_then_stop(damper_param: Option<u8>) -> Vec<f64> {
    let mut rs03 = disc_motor(Model::RS03);
    if let Some(value) = damper_param {
        write_u8(&mut rs03, 0x702A, value);
    }
    write_u8(&mut rs03, 0x7005, 2);
    enable(&mut rs03);
    write_f32(&mut rs03, 0x7018, 20.0); // limit_cur
    write_f32(&mut rs03, 0x7022, 50.0); // acc_rad
    write_f32(&mut rs03, 0x700A, 10.0); // spd_ref
    run_ms(&mut rs03, 1000);
    assert!((rs03.snapshot().speed_rad_s - 10.0).abs() < 0.2);
    let stop = CanFrame::extended(0x0400_FD01, &[0; 8]).unwrap();
    rs03.handle_frame(&stop);
    assert_eq!(rs03.snapshot().mode, ModeState::Reset);
    (0..100)
        .map(|_| {
            rs03.tick();
            rs03.snapshot().speed_rad_s
        })
        .collect()
}

#[test]
fn a_stopped_motor_brakes_a_spinning_rotor_unless_damper_is_off() {
    let braked = spin_then_stop(None);
    // Shorted windings: b = peak / no-load = 60 / 20.9 N·m·s/rad on 0.0105 kg·m² → τ ≈ 3.7 ms.
    let spec = Model::RS03.spec();
    let tau_s = (0.5 * 2.0 * 0.01 + spec.rotor_inertia_kg_m2)
        / (spec.peak_torque_nm / spec.no_load_speed_rad_s);
    let expected_10ms = 10.0 * (-0.010 / tau_s).exp();
    eprintln!(
        "stopped RS03: {:.3} rad/s after 10 ms (model {expected_10ms:.3}), {:.5} after 100 ms",
        braked[9], braked[99]
    );
    assert!((braked[9] - expected_10ms).abs() < 0.1 * expected_10ms + 0.05);
    assert!(braked[99].abs() < 0.01, "{}", braked[99]);
    // 0x702A damper = 1 disables the braking: the disc coasts.
    let coasting = spin_then_stop(Some(1));
    assert!(coasting[99] > 9.5, "{}", coasting[99]);
}

/// Read a float parameter with a type-17 request, the way a host would.
fn read_f32(motor: &mut Actuator, index: u16) -> f32 {
    let [lo, hi] = index.to_le_bytes();
    let frame = CanFrame::extended(0x1100_FD01, &[lo, hi, 0, 0, 0, 0, 0, 0]).unwrap();
    let reply = motor.handle_frame(&frame)[0];
    let d = reply.data();
    f32::from_le_bytes([d[4], d[5], d[6], d[7]])
}

#[test]
fn absurd_loads_never_put_nan_on_the_wire() {
    let loads = [
        Load::Pendulum {
            mass_kg: 1e308,
            length_m: 1e308,
        },
        Load::Disc {
            mass_kg: 1e308,
            radius_m: 1e200,
        },
        Load::Pendulum {
            mass_kg: 1e-300,
            length_m: 1e-300,
        },
    ];
    for load in loads {
        let mut config = MotorConfig::new(MOTOR, Model::RS03).with_load(load);
        config.start_angle_rad = 1.0;
        let mut rs03 = Actuator::new(config, None, 1_000_000);
        write_u8(&mut rs03, 0x7005, 3); // current mode
        enable(&mut rs03);
        write_f32(&mut rs03, 0x7006, 20.0); // iq_ref
        for _ in 0..200 {
            rs03.tick();
        }
        let snapshot = rs03.snapshot();
        assert!(snapshot.angle_rad.is_finite(), "{load:?}: {snapshot:?}");
        assert!(snapshot.speed_rad_s.is_finite(), "{load:?}: {snapshot:?}");
        // mechPos, iqf, mechVel, VBUS: every float a host can read stays finite.
        for index in [0x7019, 0x701A, 0x701B, 0x701C] {
            let value = read_f32(&mut rs03, index);
            assert!(value.is_finite(), "{load:?}: 0x{index:04X} = {value}");
        }
    }
}
