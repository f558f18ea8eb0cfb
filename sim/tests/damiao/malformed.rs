//! Malformed and stray frames: short payloads, other identifiers, extended frames, NaN
//! setpoints and random garbage never panic and get the firmware's documented reaction.

use bus::CanFrame;
use rand::{Rng, SeedableRng};
use sim::damiao::codec::{MitCommand, PosVelCommand, RegisterCmd, Special};
use sim::damiao::registers::rid;
use sim::damiao::{DamiaoMotor, Model};

use super::{answer, mit, motor, one, register, run, set_mode, special, std_frame, write};

#[test]
fn a_payload_shorter_than_its_layout_is_ignored_without_a_reply() {
    let mut m = motor(0x01, Model::DM4310);
    // A special one byte short is not a special: nothing happens.
    assert!(m.handle_frame(&std_frame(0x01, &[0xFF; 7])).is_empty());
    assert!(!m.is_enabled());
    special(&mut m, Special::Enable);
    // MIT with DLC 7.
    let data = MitCommand {
        p_des_rad: 1.0,
        kp_nm_per_rad: 50.0,
        ..MitCommand::default()
    }
    .pack(&m.registers().ranges());
    assert!(m.handle_frame(&std_frame(0x01, &data[..7])).is_empty());
    run(&mut m, 200);
    assert!(m.angle_rad().abs() < 1e-9, "the short setpoint was applied");
    // Pos-vel DLC 7, velocity DLC 3, force-position DLC 6 (each in its own mode).
    for (mode, id, len) in [(2u32, 0x101u16, 7usize), (3, 0x201, 3), (4, 0x301, 6)] {
        set_mode(&mut m, mode);
        let payload = [0x40u8; 8];
        assert!(
            m.handle_frame(&std_frame(id, &payload[..len])).is_empty(),
            "mode {mode}"
        );
        assert!(
            !m.handle_frame(&std_frame(id, &payload)).is_empty(),
            "mode {mode}"
        );
        set_mode(&mut m, 1);
    }
    // Register requests: 0..=2 bytes, a read without its RID, a write without its value.
    for len in 0..3 {
        let data = [0x01, 0x00, 0x33];
        assert!(m.handle_frame(&std_frame(0x7FF, &data[..len])).is_empty());
    }
    assert!(m
        .handle_frame(&std_frame(0x7FF, &[0x01, 0x00, 0x33]))
        .is_empty());
    assert!(m
        .handle_frame(&std_frame(0x7FF, &[0x01, 0x00, 0x55, rid::TIMEOUT, 1, 0]))
        .is_empty());
    // A 3-byte refresh is enough (it names the motor and the operation).
    let fb = answer(&mut m, std_frame(0x7FF, &[0x01, 0x00, 0xCC]));
    assert_eq!(fb.state, 1);
}

#[test]
fn frames_on_other_identifiers_or_extended_are_not_for_the_motor() {
    let mut m = motor(0x01, Model::DM4310);
    let enable = Special::Enable.payload();
    for id in [0x000u16, 0x002, 0x011, 0x401, 0x081, 0x7FE] {
        assert!(
            m.handle_frame(&std_frame(id, &enable)).is_empty(),
            "0x{id:03X}"
        );
    }
    let extended = CanFrame::extended(0x01, &enable).unwrap();
    assert!(m.handle_frame(&extended).is_empty());
    assert!(!m.is_enabled());
    // A frame for another motor does not feed this one's timeout.
    special(&mut m, Special::Enable);
    one(write(&mut m, rid::TIMEOUT, 200u32.to_le_bytes()));
    for _ in 0..30 {
        run(&mut m, 1);
        m.handle_frame(&register(0x02, RegisterCmd::Refresh, 0, [0; 4]));
    }
    assert!(!m.is_enabled(), "another motor's frames kept it alive");
}

#[test]
fn a_nan_setpoint_is_answered_and_leaves_the_target_as_it_was() {
    let mut m = motor(0x01, Model::DM4310);
    set_mode(&mut m, 2);
    special(&mut m, Special::Enable);
    let go = PosVelCommand {
        p_des_rad: 0.5,
        v_des_rad_s: 3.0,
    };
    one(m.handle_frame(&std_frame(0x101, &go.payload())));
    let nan = PosVelCommand {
        p_des_rad: f32::NAN,
        v_des_rad_s: f32::INFINITY,
    };
    let fb = answer(&mut m, std_frame(0x101, &nan.payload()));
    assert_eq!(fb.state, 1);
    run(&mut m, 1500);
    assert!((m.angle_rad() - 0.5).abs() < 0.005, "{}", m.angle_rad());
    set_mode(&mut m, 3);
    one(m.handle_frame(&std_frame(0x201, &f32::NAN.to_le_bytes())));
    run(&mut m, 200);
    assert!(m.speed_rad_s().abs() < 0.01 && m.angle_rad().is_finite());
}

#[test]
fn random_frames_never_panic_and_every_reply_is_one_well_formed_frame() {
    let mut rng = rand::rngs::SmallRng::seed_from_u64(0xDA_31A0);
    let mut m = motor(0x01, Model::DM4340);
    let mut replies = 0;
    for step in 0..20_000u32 {
        // Mostly the motor's own identifiers, so the handlers see the garbage.
        let id: u16 = match rng.random_range(0..6) {
            0 => 0x001,
            1 => 0x101,
            2 => 0x201,
            3 => 0x301,
            4 => 0x7FF,
            _ => rng.random_range(0..=0x7FF),
        };
        // Full frames half the time: most layouts need 8 bytes.
        let len = if rng.random_bool(0.5) {
            8
        } else {
            rng.random_range(0..=8usize)
        };
        let mut data = [0u8; 8];
        rng.fill(&mut data[..]);
        if id == 0x7FF && rng.random_bool(0.7) {
            // Addressed to this motor, with a known operation.
            data[..2].copy_from_slice(&1u16.to_le_bytes());
            data[2] = [0x33, 0x55, 0xAA, 0xCC][rng.random_range(0..4)];
        }
        if step % 1000 == 0 {
            // Visit every mode, so each mode's frames reach their handler.
            let mode = rng.random_range(1..=4u32);
            m.handle_frame(&register(
                1,
                RegisterCmd::Write,
                rid::CTRL_MODE,
                mode.to_le_bytes(),
            ));
        }
        let out = m.handle_frame(&std_frame(id, &data[..len]));
        assert!(out.len() <= 1, "{out:?}");
        for frame in out {
            replies += 1;
            assert!(!frame.is_extended() && frame.len() == 8, "{frame}");
            assert_eq!(frame.raw_id(), u32::from(m.mst_id()), "{frame}");
        }
        if step % 10 == 0 {
            run(&mut m, 1);
        }
        assert!(m.angle_rad().is_finite() && m.speed_rad_s().is_finite());
        assert!(m.esc_id() <= 0x7FF && m.mst_id() <= 0x7FF);
    }
    assert!(
        replies > 1000,
        "only {replies} replies: the garbage never reached a handler"
    );
}

#[test]
fn a_motor_moved_to_the_top_ids_still_never_panics() {
    // ESC_ID 0x7FE: its mode identifiers would pass 0x7FF; only MIT and registers reach it.
    let mut m = DamiaoMotor::new(sim::damiao::MotorConfig::new(0x7FE, Model::DM4310));
    assert_eq!(m.mst_id(), 0x00E);
    let reply = one(m.handle_frame(&std_frame(0x7FE, &Special::Enable.payload())));
    assert_eq!(reply.data()[0], 0x1E);
    assert!(mit(&mut m, MitCommand::default()).len() == 1);
    run(&mut m, 5);
}
