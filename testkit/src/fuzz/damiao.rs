//! Damiao: one motor's firmware and the driver's reply decoder.

use driver::damiao::codec::{self as dcodec, Feedback, Reply};
use driver::damiao::Ranges as DriverRanges;
use sim::damiao::{DamiaoMotor, Model, MotorConfig};

use super::input::{assert_finite, extended, standard, Input};

/// Most simulated milliseconds one input may run.
const MAX_TICKS: u32 = 2000;

/// The motor's ESC_ID at power-on in the emulator target (it answers on 0x11).
const ESC_ID: u16 = 0x01;

/// The driver's view of the ranges the motor's registers 21–23 hold now (a host may have
/// written them).
fn ranges_of(motor: &DamiaoMotor) -> DriverRanges {
    let r = motor.registers().ranges();
    DriverRanges::new(r.p_max_rad, r.v_max_rad_s, r.t_max_nm)
}

/// Frames and 1 ms ticks into one freshly powered Damiao motor.
///
/// Input: byte 0 picks the model; then operations: a tag byte (`% 4 == 0`: run `1..=64`
/// ticks given by the next byte; otherwise one frame: an identifier selector — mostly one of
/// the motor's present identifiers (ESC_ID, 0x100/0x200/0x300 + ESC_ID, 0x7FF with its
/// ESC_ID in D0..D1), else any 11-bit id from the input or an extended frame — a length
/// byte (mostly 8) and the payload).
///
/// Asserts: no panic; ticks send nothing (a Damiao motor speaks only when asked); every frame
/// the motor sends is an 8-byte standard frame on the MST_ID it had when the request arrived,
/// which the driver's codec reads as this motor's reply (register reply, or feedback with its
/// ESC_ID nibble) with feedback values finite and inside the ranges its registers hold;
/// angle, speed, torque and temperature stay finite.
pub fn damiao_emulator(data: &[u8]) {
    let mut input = Input::new(data);
    let model = Model::ALL[usize::from(input.byte().unwrap_or(0)) % Model::ALL.len()];
    let mut motor = DamiaoMotor::new(MotorConfig::new(ESC_ID, model));
    let mut ticks = 0u32;
    while !input.is_empty() && ticks < MAX_TICKS {
        let tag = input.byte().unwrap_or(0);
        if tag.is_multiple_of(4) {
            let n = u32::from(input.byte().unwrap_or(0) % 64) + 1;
            for _ in 0..n {
                let out = motor.tick();
                assert!(out.is_empty(), "a Damiao motor sent unasked: {out:?}");
            }
            ticks += n;
            check_motor(&motor);
        } else {
            let (esc, mst) = (motor.esc_id(), motor.mst_id());
            let frame = motor_frame(&mut input, esc);
            let out = motor.handle_frame(&frame);
            let ranges = ranges_of(&motor);
            for reply in &out {
                check_emitted(reply, esc, mst, ranges);
            }
        }
    }
}

fn motor_frame(input: &mut Input<'_>, esc: u16) -> bus::CanFrame {
    let sel = input.byte().unwrap_or(0);
    if sel >= 0xF8 {
        // Extended frames: the motor must ignore them.
        let id = input.u32();
        return extended(id, &input.payload());
    }
    let id = match sel % 8 {
        0..=2 => esc,
        3 => esc + 0x100,
        4 => esc + 0x200,
        5 => esc + 0x300,
        6 => 0x7FF,
        _ => input.u16(),
    };
    let len = if input.byte().unwrap_or(0) < 0xF0 {
        8
    } else {
        usize::from(input.byte().unwrap_or(0) % 9)
    };
    let mut payload = input.take(len).to_vec();
    payload.resize(len, 0);
    // A register request names its motor in D0..D1: this one, unless the selector's top bit
    // leaves the input's bytes there.
    if sel % 8 == 6 && sel < 0x80 && payload.len() >= 2 {
        payload[..2].copy_from_slice(&esc.to_le_bytes());
    }
    standard(id, &payload)
}

fn check_emitted(frame: &bus::CanFrame, esc: u16, mst: u16, ranges: DriverRanges) {
    assert!(
        !frame.is_extended(),
        "Damiao motor sent an extended frame: {frame}"
    );
    assert_eq!(frame.len(), 8, "Damiao motor sent a short frame: {frame}");
    assert_eq!(
        frame.raw_id(),
        u32::from(mst),
        "a reply off the MST_ID 0x{mst:03X}: {frame}"
    );
    assert!(
        ranges.is_valid(),
        "the motor holds ranges no host could decode with: {ranges:?}"
    );
    match dcodec::decode_reply(frame, esc, &ranges) {
        Some(Reply::Feedback(f)) => check_feedback(&f, ranges),
        Some(Reply::Register(r)) => assert_eq!(r.esc_id, esc),
        None => panic!("the driver does not read {frame} as the reply of ESC_ID 0x{esc:03X}"),
    }
}

fn check_feedback(f: &Feedback, r: DriverRanges) {
    let within =
        |v: f32, max: f32| v.is_finite() && f64::from(v).abs() <= f64::from(max) * (1.0 + 1e-6);
    assert!(
        within(f.position_rad, r.pmax),
        "position {} outside ±{}",
        f.position_rad,
        r.pmax
    );
    assert!(
        within(f.velocity_rad_s, r.vmax),
        "velocity {} outside ±{}",
        f.velocity_rad_s,
        r.vmax
    );
    assert!(
        within(f.torque_nm, r.tmax),
        "torque {} outside ±{}",
        f.torque_nm,
        r.tmax
    );
}

fn check_motor(m: &DamiaoMotor) {
    assert_finite(
        "damiao motor",
        &[
            m.angle_rad(),
            m.speed_rad_s(),
            m.torque_nm(),
            m.coil_temperature_c(),
            m.mos_temperature_c(),
            m.bus_voltage_v(),
        ],
    );
}

/// Arbitrary frames into the driver's Damiao reply decoder.
///
/// Input: repeated items: a model byte, the ESC_ID the decoder expects (two bytes, 11 bits),
/// a selector, and a frame: mostly an 8-byte standard frame (selector below 0xF0), else one
/// of any length (0xF0..0xF7), an extended frame (0xF8..0xFB), or an 8-byte frame decoded
/// with ranges read from the input as three f32 (0xFC.., as a host reads them from registers
/// 21–23; ranges the driver would refuse are skipped).
///
/// Asserts: no panic; feedback is finite and inside the ranges; a register reply names the
/// ESC_ID asked; `decode_feedback` of the same bytes gives the same feedback.
pub fn damiao_driver_decode(data: &[u8]) {
    let mut input = Input::new(data);
    while !input.is_empty() {
        let model = Model::ALL[usize::from(input.byte().unwrap_or(0)) % Model::ALL.len()];
        let esc = input.u16() & 0x7FF;
        let sel = input.byte().unwrap_or(0);
        let mut ranges = driver_ranges(model);
        let frame = match sel {
            0..=0xEF => {
                let id = input.u16();
                let mut payload = input.take(8).to_vec();
                payload.resize(8, 0);
                standard(id, &payload)
            }
            0xF0..=0xF7 => {
                let id = input.u16();
                standard(id, &input.payload())
            }
            0xF8..=0xFB => {
                let id = input.u32();
                extended(id, &input.payload())
            }
            _ => {
                let mut f = || f32::from_le_bytes(input.u32().to_le_bytes());
                ranges = DriverRanges::new(f(), f(), f());
                let id = input.u16();
                let mut payload = input.take(8).to_vec();
                payload.resize(8, 0);
                standard(id, &payload)
            }
        };
        if !ranges.is_valid() {
            continue;
        }
        match dcodec::decode_reply(&frame, esc, &ranges) {
            Some(Reply::Feedback(f)) => {
                check_feedback(&f, ranges);
                assert_eq!(dcodec::decode_feedback(frame.data(), &ranges), Some(f));
            }
            Some(Reply::Register(r)) => assert_eq!(r.esc_id, esc),
            None => {}
        }
    }
}

/// The driver's ranges of the emulator's model `model` (the current table, as the emulator
/// serves them).
fn driver_ranges(model: Model) -> DriverRanges {
    driver::damiao::Model::parse(model.name())
        .expect("the driver knows every emulated model")
        .ranges(driver::damiao::RangeTable::Current)
}
