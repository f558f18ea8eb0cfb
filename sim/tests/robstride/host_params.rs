//! Type-17 reads of the host-tool tables (0x20xx configuration, 0x30xx observation): the
//! indices the official Python SDK reads (0x2005 MechOffset, 0x3016 mechPos, 0x3017 mechVel,
//! 0x302C torque_fdb) answer with status 0 and the live values, on every model's own layout
//! (RS04 shifted by one); observation rows refuse writes; configuration mirrors write through.
//! Before this, all of them answered the failure flag with zeros.

use bus::CanFrame;
use sim::robstride::{Actuator, Load, Model, MotorConfig, DEFAULT_HOST_ID};

const HOST: u8 = DEFAULT_HOST_ID;

fn motor(can_id: u8, model: Model) -> Actuator {
    let mut config = MotorConfig::new(can_id, model).with_load(Load::Pendulum {
        mass_kg: 0.5,
        length_m: 0.2,
    });
    config.uid = Some([1, 2, 3, 4, 5, 6, 7, 8]);
    config.start_angle_rad = 0.8;
    Actuator::new(config, None, 1_000_000)
}

fn ext(comm: u32, motor: u8, data: [u8; 8]) -> CanFrame {
    CanFrame::extended(
        (comm << 24) | (u32::from(HOST) << 8) | u32::from(motor),
        &data,
    )
    .unwrap()
}

/// A type-17 read: (status byte, value bytes) of the single reply.
fn read(m: &mut Actuator, index: u16) -> (u8, [u8; 4]) {
    let [lo, hi] = index.to_le_bytes();
    let replies = m.handle_frame(&ext(17, m.can_id(), [lo, hi, 0, 0, 0, 0, 0, 0]));
    assert_eq!(replies.len(), 1, "{replies:?}");
    let reply = replies[0];
    assert_eq!(reply.raw_id() >> 24, 17);
    assert_eq!(reply.raw_id() & 0xFF, u32::from(HOST));
    let d = reply.data();
    let status = ((reply.raw_id() >> 16) & 0xFF) as u8;
    // A success echoes the index; the failure echo is all zeros, as captured on hardware.
    let echo = if status == 0 { [lo, hi] } else { [0, 0] };
    assert_eq!(&d[..2], &echo, "index echo");
    (status, [d[4], d[5], d[6], d[7]])
}

fn read_f32(m: &mut Actuator, index: u16) -> f32 {
    let (status, bytes) = read(m, index);
    assert_eq!(status, 0, "index {index:#06x} answered the failure flag");
    f32::from_le_bytes(bytes)
}

fn read_u32(m: &mut Actuator, index: u16) -> u32 {
    let (status, bytes) = read(m, index);
    assert_eq!(status, 0, "index {index:#06x} answered the failure flag");
    u32::from_le_bytes(bytes)
}

fn write(m: &mut Actuator, index: u16, value: [u8; 4]) -> CanFrame {
    let [lo, hi] = index.to_le_bytes();
    let data = [lo, hi, 0, 0, value[0], value[1], value[2], value[3]];
    let replies = m.handle_frame(&ext(18, m.can_id(), data));
    assert_eq!(replies.len(), 1, "{replies:?}");
    replies[0]
}

/// Let the pendulum (released at 0.8 rad, motor off) swing for `ms`.
fn run(m: &mut Actuator, ms: u32) {
    for _ in 0..ms {
        m.tick();
    }
}

#[test]
fn the_sdk_indices_read_live_values_with_status_ok() {
    for model in [
        Model::RS00,
        Model::RS02,
        Model::RS03,
        Model::RS05,
        Model::RS06,
    ] {
        let mut m = motor(0x7F, model);
        run(&mut m, 120);
        let snap = m.snapshot();
        assert!(snap.speed_rad_s.abs() > 0.05, "{model:?}: the load moves");
        let mech_pos = read_f32(&mut m, 0x3016);
        let mech_vel = read_f32(&mut m, 0x3017);
        assert!(
            (f64::from(mech_pos) - snap.angle_rad).abs() < 1e-5,
            "{model:?}"
        );
        assert!(
            (f64::from(mech_vel) - snap.speed_rad_s).abs() < 1e-5,
            "{model:?}"
        );
        // The 0x70xx copies agree.
        assert_eq!(mech_pos, read_f32(&mut m, 0x7019), "{model:?}");
        assert_eq!(mech_vel, read_f32(&mut m, 0x701B), "{model:?}");
        let torque_index = if model == Model::RS06 { 0x302D } else { 0x302C };
        assert_eq!(
            f64::from(read_f32(&mut m, torque_index)),
            f64::from(snap.torque_nm as f32),
            "{model:?}"
        );
        assert_eq!(read_f32(&mut m, 0x2005), 0.0, "{model:?}: no zero set yet");
        assert_eq!(read_u32(&mut m, 0x3022), 0, "{model:?}: faultSta");
    }
}

#[test]
fn rs04_observation_rows_are_shifted_by_one() {
    let mut m = motor(0x7F, Model::RS04);
    run(&mut m, 120);
    let snap = m.snapshot();
    assert!((f64::from(read_f32(&mut m, 0x3017)) - snap.angle_rad).abs() < 1e-5);
    assert!((f64::from(read_f32(&mut m, 0x3018)) - snap.speed_rad_s).abs() < 1e-5);
    // 0x3016 is modPos on RS04: the angle within one turn.
    let mod_pos = f64::from(read_f32(&mut m, 0x3016));
    assert!((mod_pos - snap.angle_rad.rem_euclid(std::f64::consts::TAU)).abs() < 1e-5);
}

#[test]
fn mech_offset_follows_the_zero_and_temperatures_read_times_ten() {
    let mut m = motor(0x7F, Model::RS03);
    // Type 6: the present angle becomes 0; MechOffset holds it.
    m.handle_frame(&ext(6, 0x7F, [1, 0, 0, 0, 0, 0, 0, 0]));
    assert!((read_f32(&mut m, 0x2005) - 0.8).abs() < 1e-6);
    assert!(read_f32(&mut m, 0x3016).abs() < 1e-6);
    m.set_temperature(61.5);
    let (status, bytes) = read(&mut m, 0x3006);
    assert_eq!((status, i16::from_le_bytes([bytes[0], bytes[1]])), (0, 615));
    assert_eq!(bytes[2..], [0, 0]);
    m.set_bus_voltage(47.5);
    assert_eq!(read_f32(&mut m, 0x300C), 47.5);
}

#[test]
fn configuration_rows_show_ids_timeout_and_the_pending_protocol() {
    // Layout B (RS03): CAN_ID 0x2009, CAN_MASTER 0x200a, CAN_TIMEOUT 0x200b, protocol_1 0x2025.
    let mut m = motor(0x21, Model::RS03);
    assert_eq!(read(&mut m, 0x2009), (0, [0x21, 0, 0, 0]));
    assert_eq!(read(&mut m, 0x200a), (0, [HOST, 0, 0, 0]));
    assert_eq!(read(&mut m, 0x2025), (0, [0, 0, 0, 0]));
    m.handle_frame(&ext(25, 0x21, [1, 2, 3, 4, 5, 6, 2, 0]));
    assert_eq!(
        read(&mut m, 0x2025),
        (0, [2, 0, 0, 0]),
        "MIT after power cycle"
    );
    // Layout A (RS00): CAN_ID at 0x200a, CAN_TIMEOUT at 0x200c.
    let mut m = motor(0x05, Model::RS00);
    assert_eq!(read(&mut m, 0x200a), (0, [0x05, 0, 0, 0]));
    // CAN_TIMEOUT mirrors canTimeout (0x7028): a write through either reads on both.
    let reply = write(&mut m, 0x200c, 20_000u32.to_le_bytes());
    assert_eq!(reply.raw_id() >> 24, 2, "a write that lands replies type 2");
    assert_eq!(read_u32(&mut m, 0x7028), 20_000);
    assert_eq!(read_u32(&mut m, 0x200c), 20_000);
}

#[test]
fn observation_and_command_owned_rows_refuse_writes_and_strings_fail() {
    let mut m = motor(0x7F, Model::RS03);
    for index in [0x3016u16, 0x3022, 0x2009, 0x2025, 0x2005] {
        let reply = write(&mut m, index, 1.0f32.to_le_bytes());
        assert_eq!(reply.raw_id(), 0x1101_7FFD, "{index:#06x}");
        assert_eq!(reply.data()[..2], index.to_le_bytes());
    }
    assert_eq!(m.can_id(), 0x7F);
    // Strings (0x0000 Name, 0x1003 AppCodeVersion) and opaque rows answer the failure flag
    // with a zero payload, as captured on hardware.
    for index in [0x0000u16, 0x1003, 0x2000, 0x3008] {
        assert_eq!(read(&mut m, index).0, 1, "{index:#06x}");
    }
}
