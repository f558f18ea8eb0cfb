//! RobStride: one actuator's firmware and the driver's reply decoder.

use std::time::Duration;

use driver::robstride::codec::{self as dcodec, Incoming};
use driver::robstride::{Model as DriverModel, RangeTable as DriverTable, Ranges as DriverRanges};
use sim::robstride::{Actuator, Model, MotorConfig, MotorSnapshot};

use super::input::{assert_finite, extended, standard, Input};

/// Most simulated milliseconds one input may run.
const MAX_TICKS: u32 = 2000;

/// The motor's CAN ID in the emulator target.
const MOTOR_ID: u8 = 0x7F;

/// The driver's ranges of the emulator's model `model` (same manual table).
pub(crate) fn driver_ranges(model: Model) -> DriverRanges {
    DriverModel::parse(&format!("{model:?}"))
        .expect("the driver knows every emulated model")
        .ranges(DriverTable::Manual)
}

/// Frames and 1 ms ticks into one freshly powered RobStride actuator.
///
/// Input: byte 0 picks the model; then operations: a tag byte (`% 4 == 0`: run `1..=64`
/// ticks given by the next byte; otherwise one frame: comm type byte, two bytes of data
/// area 2, a destination selector — mostly this motor — and the payload, usually 8 bytes).
///
/// Asserts: no panic; every frame the motor sends is an 8-byte extended frame; status frames
/// decode (driver codec) to finite values inside the model's ranges; the simulated angle,
/// speed, torque, current, temperature and voltage stay finite.
pub fn robstride_emulator(data: &[u8]) {
    let mut input = Input::new(data);
    let model = Model::ALL[usize::from(input.byte().unwrap_or(0)) % Model::ALL.len()];
    let ranges = driver_ranges(model);
    let mut motor = Actuator::new(MotorConfig::new(MOTOR_ID, model), None, 1_000_000);
    let mut ticks = 0u32;
    while !input.is_empty() && ticks < MAX_TICKS {
        let tag = input.byte().unwrap_or(0);
        let out = if tag.is_multiple_of(4) {
            let n = u32::from(input.byte().unwrap_or(0) % 64) + 1;
            let mut out = Vec::new();
            for _ in 0..n {
                out.extend(motor.tick());
            }
            ticks += n;
            check_snapshot(&motor.snapshot());
            out
        } else {
            motor.handle_frame(&motor_frame(&mut input))
        };
        for frame in &out {
            check_emitted(frame, ranges);
        }
    }
}

fn motor_frame(input: &mut Input<'_>) -> bus::CanFrame {
    let comm = input.byte().unwrap_or(0) % 32;
    let data2 = input.u16();
    let dst = match input.byte().unwrap_or(0) {
        0..=0xDF => MOTOR_ID,
        0xE0..=0xEF => 0,
        0xF0..=0xFD => input.byte().unwrap_or(0),
        // A standard frame now and then: the motor must ignore it.
        _ => return standard(data2, &input.payload()),
    };
    let len = if input.byte().unwrap_or(0) < 0xF0 {
        8
    } else {
        usize::from(input.byte().unwrap_or(0) % 9)
    };
    let mut payload = input.take(len).to_vec();
    payload.resize(len, 0);
    let id = (u32::from(comm) << 24) | (u32::from(data2) << 8) | u32::from(dst);
    extended(id, &payload)
}

fn check_emitted(frame: &bus::CanFrame, ranges: DriverRanges) {
    assert!(
        frame.is_extended(),
        "RobStride motor sent a standard frame: {frame}"
    );
    assert_eq!(
        frame.len(),
        8,
        "RobStride motor sent a short frame: {frame}"
    );
    let host = (frame.raw_id() & 0xFF) as u8;
    if let Some(Incoming::Feedback(f)) =
        dcodec::decode(frame, host, Duration::ZERO, |_| Some(ranges))
    {
        check_feedback(&f, ranges);
    }
}

fn check_feedback(f: &driver::robstride::Feedback, r: DriverRanges) {
    let within = |v: f32, max: f32| v.is_finite() && v.abs() <= max * (1.0 + 1e-6);
    assert!(
        within(f.angle_rad, r.angle_rad),
        "angle {} outside ±{}",
        f.angle_rad,
        r.angle_rad
    );
    assert!(
        within(f.speed_rad_s, r.speed_rad_s),
        "speed {}",
        f.speed_rad_s
    );
    assert!(within(f.torque_nm, r.torque_nm), "torque {}", f.torque_nm);
    assert!(f.temperature_c.is_finite());
}

fn check_snapshot(s: &MotorSnapshot) {
    assert_finite(
        "robstride snapshot",
        &[
            s.angle_rad,
            s.speed_rad_s,
            s.torque_nm,
            s.iq_a,
            s.temperature_c,
            s.bus_voltage_v,
        ],
    );
}

/// Arbitrary frames into the driver's RobStride decoder.
///
/// Input: byte 0 picks the host ID; then repeated (model byte, id selector, payload). Mostly
/// 8-byte extended frames addressed to that host.
///
/// Asserts: no panic; status feedback is finite and inside the model's ranges.
pub fn robstride_driver_decode(data: &[u8]) {
    let mut input = Input::new(data);
    let host = input.byte().unwrap_or(0xFD);
    while !input.is_empty() {
        let model = Model::ALL[usize::from(input.byte().unwrap_or(0)) % Model::ALL.len()];
        let ranges = driver_ranges(model);
        let sel = input.byte().unwrap_or(0);
        let frame = if sel < 0xF0 {
            // Comm type from the selector, the motor ID and data area 2 from the input, this host.
            let high = u32::from(input.u16());
            let id = (u32::from(sel % 32) << 24) | (high << 8) | u32::from(host);
            let mut payload = input.take(8).to_vec();
            payload.resize(8, 0);
            extended(id, &payload)
        } else if sel < 0xF8 {
            let id = input.u32();
            extended(id, &input.payload())
        } else {
            let id = input.u16();
            standard(id, &input.payload())
        };
        let ts = Duration::from_micros(u64::from(sel));
        match dcodec::decode(&frame, host, ts, |_| Some(ranges)) {
            Some(Incoming::Feedback(f)) => check_feedback(&f, ranges),
            Some(other) => {
                let _ = other.motor_id();
            }
            None => {}
        }
    }
}
