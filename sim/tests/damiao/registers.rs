//! Registers over 0x7FF: read, write, refused and read-only writes echoed unchanged, unknown
//! RIDs silent, the mode switch, moving the ids, save and the flash round trip, refresh.

use sim::actuator::ActuatorFirmware;
use sim::damiao::codec::{MitCommand, RegisterCmd, Special};
use sim::damiao::registers::rid;
use sim::damiao::{DamiaoMotor, Model, MotorConfig};

use super::{answer, decode, mit, motor, one, register, run, set_mode, special, std_frame, write};

fn read(m: &mut DamiaoMotor, rid: u8) -> Vec<bus::CanFrame> {
    m.handle_frame(&register(m.esc_id(), RegisterCmd::Read, rid, [0; 4]))
}

fn value_bytes(frame: &bus::CanFrame) -> [u8; 4] {
    frame.data()[4..8].try_into().unwrap()
}

#[test]
fn a_read_answers_on_mst_id_with_the_request_s_layout() {
    let mut m = motor(0x01, Model::DM4310);
    let reply = one(read(&mut m, rid::CTRL_MODE));
    assert_eq!(reply.raw_id(), 0x11);
    assert_eq!(reply.data(), [0x01, 0x00, 0x33, 0x0A, 1, 0, 0, 0]);
    let vmax = one(read(&mut m, rid::VMAX));
    assert_eq!(value_bytes(&vmax), 30.0f32.to_le_bytes());
    let gear = one(read(&mut m, rid::GR));
    assert_eq!(value_bytes(&gear), 10.0f32.to_le_bytes());
    // A DM4340 serves its own VMAX (10, not the older tables' 8).
    let mut j3 = motor(0x03, Model::DM4340);
    let reply = one(read(&mut j3, rid::VMAX));
    assert_eq!(reply.raw_id(), 0x13);
    assert_eq!(reply.data()[..4], [0x03, 0x00, 0x33, 22]);
    assert_eq!(value_bytes(&reply), 10.0f32.to_le_bytes());
}

#[test]
fn a_write_stores_and_echoes_with_0x55() {
    let mut m = motor(0x01, Model::DM4310);
    let echo = one(write(&mut m, rid::TIMEOUT, 400u32.to_le_bytes()));
    assert_eq!(echo.raw_id(), 0x11);
    assert_eq!(echo.data(), [0x01, 0x00, 0x55, 0x09, 0x90, 0x01, 0, 0]);
    let back = one(read(&mut m, rid::TIMEOUT));
    assert_eq!(value_bytes(&back), 400u32.to_le_bytes());
    let echo = one(write(&mut m, rid::ACC, 12.5f32.to_le_bytes()));
    assert_eq!(value_bytes(&echo), 12.5f32.to_le_bytes());
}

#[test]
fn refused_and_read_only_writes_echo_the_unchanged_value() {
    let mut m = motor(0x01, Model::DM4310);
    // Read-only: Gr stays 10.
    let echo = one(write(&mut m, rid::GR, 3.0f32.to_le_bytes()));
    assert_eq!(echo.data()[..4], [0x01, 0x00, 0x55, rid::GR]);
    assert_eq!(value_bytes(&echo), 10.0f32.to_le_bytes());
    // Out of the note's ranges: CTRL_MODE 1..=4, OT_Value [80, 200), DEC < 0; PMAX > 0.
    for (rid, bad, held) in [
        (rid::CTRL_MODE, 9u32.to_le_bytes(), 1u32.to_le_bytes()),
        (
            rid::OT_VALUE,
            250.0f32.to_le_bytes(),
            120.0f32.to_le_bytes(),
        ),
        (rid::DEC, 5.0f32.to_le_bytes(), (-30.0f32).to_le_bytes()),
        (rid::PMAX, 0.0f32.to_le_bytes(), 12.5f32.to_le_bytes()),
        (rid::ACC, f32::NAN.to_le_bytes(), 30.0f32.to_le_bytes()),
        (rid::ESC_ID, 0x800u32.to_le_bytes(), 1u32.to_le_bytes()),
    ] {
        let echo = one(write(&mut m, rid, bad));
        assert_eq!(value_bytes(&echo), held, "rid {rid}");
        assert_eq!(value_bytes(&one(read(&mut m, rid))), held, "rid {rid}");
    }
}

#[test]
fn an_unknown_rid_or_another_motor_s_request_gets_no_reply() {
    let mut m = motor(0x01, Model::DM4310);
    for unknown in [37u8, 40, 57, 70, 99, 255] {
        assert!(read(&mut m, unknown).is_empty(), "read {unknown}");
        assert!(
            write(&mut m, unknown, [1, 0, 0, 0]).is_empty(),
            "write {unknown}"
        );
    }
    // ESC_ID 2's request, and one for ESC_ID 0x101 (D1 matters too).
    assert!(m
        .handle_frame(&register(0x02, RegisterCmd::Read, rid::CTRL_MODE, [0; 4]))
        .is_empty());
    assert!(m
        .handle_frame(&register(0x101, RegisterCmd::Read, rid::CTRL_MODE, [0; 4]))
        .is_empty());
    // An unknown operation byte.
    assert!(m
        .handle_frame(&std_frame(0x7FF, &[0x01, 0x00, 0x44, 10, 0, 0, 0, 0]))
        .is_empty());
}

#[test]
fn writing_ctrl_mode_switches_which_commands_are_answered() {
    let mut m = motor(0x01, Model::DM4310);
    special(&mut m, Special::Enable);
    assert!(m
        .handle_frame(&std_frame(0x201, &4.0f32.to_le_bytes()))
        .is_empty());
    set_mode(&mut m, 3);
    assert_eq!(
        value_bytes(&one(read(&mut m, rid::CTRL_MODE))),
        3u32.to_le_bytes()
    );
    assert_eq!(m.snapshot().mode, "velocity");
    // Switched while enabled: the new mode runs at once.
    let fb = answer(&mut m, std_frame(0x201, &4.0f32.to_le_bytes()));
    assert_eq!(fb.state, 1);
    run(&mut m, 600);
    assert!((m.speed_rad_s() - 4.0).abs() < 0.05, "{}", m.speed_rad_s());
    assert!(mit(&mut m, MitCommand::default()).is_empty());
}

#[test]
fn pmax_rescales_the_mit_position_field() {
    let mut m = motor(0x01, Model::DM4310);
    let echo = one(write(&mut m, rid::PMAX, 3.0f32.to_le_bytes()));
    assert_eq!(value_bytes(&echo), 3.0f32.to_le_bytes());
    special(&mut m, Special::Enable);
    // p_des raw 0xFFFF is +PMAX: 3 rad now, not 12.5.
    let top = MitCommand {
        p_des_rad: 3.0,
        kp_nm_per_rad: 30.0,
        kd_nm_s_per_rad: 1.0,
        ..MitCommand::default()
    };
    let data = top.pack(&m.registers().ranges());
    assert_eq!(data[..2], [0xFF, 0xFF]);
    one(m.handle_frame(&std_frame(0x01, &data)));
    run(&mut m, 2000);
    assert!((m.angle_rad() - 3.0).abs() < 0.01, "{}", m.angle_rad());
}

#[test]
fn moving_esc_id_answers_where_the_host_waits_then_listens_on_the_new_id() {
    let mut m = motor(0x01, Model::DM4310);
    let echo = one(write(&mut m, rid::ESC_ID, 5u32.to_le_bytes()));
    assert_eq!(echo.raw_id(), 0x11);
    assert_eq!(echo.data()[..4], [0x01, 0x00, 0x55, rid::ESC_ID]);
    assert_eq!(m.esc_id(), 5);
    assert_eq!(m.can_id(), 5);
    assert!(m
        .handle_frame(&std_frame(0x01, &Special::Enable.payload()))
        .is_empty());
    let reply = one(m.handle_frame(&std_frame(0x05, &Special::Enable.payload())));
    assert_eq!(reply.raw_id(), 0x11);
    assert_eq!(reply.data()[0], 0x15, "state 1, id nibble 5");
    // MST_ID moves the same way.
    let echo = one(write(&mut m, rid::MST_ID, 0x25u32.to_le_bytes()));
    assert_eq!(echo.raw_id(), 0x11);
    let reply = one(m.handle_frame(&std_frame(0x05, &Special::Disable.payload())));
    assert_eq!(reply.raw_id(), 0x25);
}

#[test]
fn save_keeps_the_registers_for_the_next_power_on() {
    let mut m = motor(0x01, Model::DM8009);
    one(write(&mut m, rid::TIMEOUT, 2000u32.to_le_bytes()));
    one(write(&mut m, rid::CTRL_MODE, 2u32.to_le_bytes()));
    one(write(&mut m, rid::ESC_ID, 7u32.to_le_bytes()));
    assert!(!m.take_persist_request(), "written, not yet saved");
    // Save: no reply, a persist request, the image holds the values.
    assert!(m
        .handle_frame(&register(7, RegisterCmd::Save, 0, [0; 4]))
        .is_empty());
    assert!(m.take_persist_request());
    let image = m.persisted();
    assert_eq!(image["registers"]["TIMEOUT"], 2000.0);
    assert_eq!(image["registers"]["ESC_ID"], 7.0);
    assert!(
        image["registers"].get("Gr").is_none(),
        "read-only registers are not saved"
    );
    // Power on again from it.
    let config = MotorConfig::from_persisted(Model::DM8009, &image).unwrap();
    assert_eq!((config.esc_id, config.mst_id), (7, 0x11), "MST_ID as saved");
    let mut again = DamiaoMotor::new(config);
    assert_eq!(again.esc_id(), 7);
    assert_eq!(
        value_bytes(&one(read(&mut again, rid::TIMEOUT))),
        2000u32.to_le_bytes()
    );
    assert_eq!(again.snapshot().mode, "pos_vel");
    // A write after the save is not in flash until the next save.
    one(write(&mut again, rid::TIMEOUT, 10u32.to_le_bytes()));
    assert_eq!(again.persisted()["registers"]["TIMEOUT"], 2000.0);
}

#[test]
fn save_is_ignored_while_enabled() {
    let mut m = motor(0x01, Model::DM4310);
    one(write(&mut m, rid::TIMEOUT, 100u32.to_le_bytes()));
    special(&mut m, Special::Enable);
    assert!(m
        .handle_frame(&register(1, RegisterCmd::Save, 1, [0; 4]))
        .is_empty());
    assert!(!m.take_persist_request());
    assert_eq!(m.persisted()["registers"]["TIMEOUT"], 0.0);
}

#[test]
fn refresh_answers_with_feedback_and_live_registers_follow_the_shaft() {
    let mut m = motor(0x01, Model::DM4310);
    m.set_external_torque(0.05);
    run(&mut m, 200);
    let reply = one(m.handle_frame(&register(1, RegisterCmd::Refresh, 0, [0; 4])));
    let fb = decode(&m, reply);
    assert_eq!(fb.state, 0);
    assert!((fb.position_rad - m.angle_rad()).abs() < 0.001);
    let xout = f32::from_le_bytes(value_bytes(&one(read(&mut m, rid::XOUT))));
    assert!((f64::from(xout) - m.angle_rad()).abs() < 1e-5);
    let p_m = f32::from_le_bytes(value_bytes(&one(read(&mut m, rid::P_M))));
    assert!(
        (f64::from(p_m) - 10.0 * m.angle_rad()).abs() < 1e-4,
        "gear 10"
    );
    let vbus = f32::from_le_bytes(value_bytes(&one(read(&mut m, rid::VBUS))));
    assert_eq!(vbus, 24.0);
}
