//! Property tests of the Damiao codec: truncating quantisation within one step, the MIT bit
//! packing unpacked by hand, f32 and register payloads that survive the wire, and decoding
//! that never panics on any frame.

use bus::CanFrame;
use driver::damiao::codec::{self, from_uint, op, to_uint, KD_MAX, KP_MAX};
use driver::damiao::{
    ForcePosCommand, MitCommand, Model, RangeTable, RegisterKind, RegisterValue, Reply, VelocityLen,
};
use proptest::prelude::*;

fn any_model() -> impl Strategy<Value = Model> {
    proptest::sample::select(Model::ALL.to_vec())
}

/// The five fields of an MIT payload, unpacked bit by bit.
fn unpack_mit(d: &[u8]) -> [u16; 5] {
    let w = |i: usize| u16::from(d[i]);
    [
        (w(0) << 8) | w(1),
        (w(2) << 4) | (w(3) >> 4),
        ((w(3) & 0x0F) << 8) | w(4),
        (w(5) << 4) | (w(6) >> 4),
        ((w(6) & 0x0F) << 8) | w(7),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Encoding truncates: the decoded value is never above the input and at most one step
    /// below it (the bottom of the range decodes exactly).
    #[test]
    fn quantisation_truncates_within_one_step(
        fraction in 0.0f64..=1.0, half in 0.5f32..300.0, bits in proptest::sample::select(vec![12u32, 16]),
    ) {
        let (lo, hi) = (-half, half);
        let x = (f64::from(lo) + fraction * f64::from(hi - lo)) as f32;
        let x = x.clamp(lo, hi);
        let raw = to_uint(x, lo, hi, bits);
        prop_assert!(u32::from(raw) < (1 << bits));
        let back = f64::from(from_uint(raw, lo, hi, bits));
        let step = f64::from(hi - lo) / f64::from((1u32 << bits) - 1);
        let slack = 1e-6 * f64::from(half);
        prop_assert!(back <= f64::from(x) + slack, "{x} -> {raw} -> {back}");
        prop_assert!(f64::from(x) - back < step + slack, "{x} -> {raw} -> {back}");
    }

    /// Any MIT command, NaN and infinities included, packs without panicking into fields that
    /// decode within one step below the clamped value.
    #[test]
    fn mit_fields_unpack_to_the_clamped_values(
        model in any_model(), esc in 0u16..=0x7FF,
        p: f32, v: f32, kp: f32, kd: f32, t: f32,
    ) {
        let r = model.ranges(RangeTable::Current);
        let cmd = MitCommand { p_des_rad: p, v_des_rad_s: v, kp, kd, t_ff_nm: t };
        let frame = codec::mit(esc, &cmd, &r).unwrap();
        prop_assert_eq!(frame.raw_id(), u32::from(esc));
        let fields = unpack_mit(frame.data());
        let spec = [
            (p, -r.pmax, r.pmax, 16), (v, -r.vmax, r.vmax, 12), (kp, 0.0, KP_MAX, 12),
            (kd, 0.0, KD_MAX, 12), (t, -r.tmax, r.tmax, 12),
        ];
        for (raw, (x, lo, hi, bits)) in fields.into_iter().zip(spec) {
            prop_assert!(u32::from(raw) < (1 << bits));
            if x.is_nan() {
                prop_assert_eq!(raw, 0);
                continue;
            }
            let clamped = f64::from(x.clamp(lo, hi));
            let back = f64::from(from_uint(raw, lo, hi, bits));
            let step = f64::from(hi - lo) / f64::from((1u32 << bits) - 1);
            prop_assert!(back <= clamped + 1e-4 && clamped - back < step + 1e-4,
                "{x} in {lo}..{hi} -> {raw} -> {back}");
        }
    }

    /// The f32 commands carry their values bit for bit; the force-position limits are the
    /// rounded, clamped scaled values.
    #[test]
    fn mode_commands_carry_their_values(
        esc in 0u16..=0x4FE, p: f32, v: f32, limit in -10.0f32..200.0, current in -1.0f32..2.0,
    ) {
        let frame = codec::pos_vel(esc, p, v).unwrap();
        prop_assert_eq!(frame.raw_id(), 0x100 + u32::from(esc));
        prop_assert_eq!(&frame.data()[..4], &p.to_le_bytes()[..]);
        prop_assert_eq!(&frame.data()[4..], &v.to_le_bytes()[..]);
        for (len, dlc) in [(VelocityLen::Four, 4), (VelocityLen::Eight, 8)] {
            let frame = codec::velocity(esc, v, len).unwrap();
            prop_assert_eq!(frame.raw_id(), 0x200 + u32::from(esc));
            prop_assert_eq!(frame.len(), dlc);
            prop_assert_eq!(&frame.data()[..4], &v.to_le_bytes()[..]);
            prop_assert!(frame.data()[4..].iter().all(|b| *b == 0));
        }
        let cmd = ForcePosCommand { p_des_rad: p, v_limit_rad_s: limit, i_limit: current };
        let frame = codec::force_position(esc, &cmd).unwrap();
        prop_assert_eq!(frame.raw_id(), 0x300 + u32::from(esc));
        let d = frame.data();
        prop_assert_eq!(&d[..4], &p.to_le_bytes()[..]);
        let speed = u16::from_le_bytes([d[4], d[5]]);
        let amps = u16::from_le_bytes([d[6], d[7]]);
        let want_speed = (f64::from(limit) * 100.0).round().clamp(0.0, 10_000.0);
        let want_amps = (f64::from(current) * 10_000.0).round().clamp(0.0, 10_000.0);
        prop_assert_eq!(f64::from(speed), want_speed);
        prop_assert_eq!(f64::from(amps), want_amps);
    }

    /// A write's echo (the request's payload on MST_ID) decodes as the register reply of the
    /// same motor, RID and value.
    #[test]
    fn register_write_echoes_decode_to_what_was_written(
        esc in 0u16..=0x4FE, mst in 0u16..=0x7FE, rid: u8, bits: u32,
    ) {
        let kind = RegisterKind::of_rid(rid);
        let value = RegisterValue::from_bytes(kind, bits.to_le_bytes());
        let request = codec::write_register(esc, rid, value).unwrap();
        prop_assert_eq!(request.raw_id(), 0x7FF);
        let echo = CanFrame::standard(mst, request.data()).unwrap();
        let r = Model::DM4310.ranges(RangeTable::Current);
        let Some(Reply::Register(reply)) = codec::decode_reply(&echo, esc, &r) else {
            return Err(TestCaseError::fail("not a register reply"));
        };
        prop_assert_eq!((reply.esc_id, reply.op, reply.rid), (esc, op::WRITE, rid));
        prop_assert_eq!(RegisterValue::from_bytes(kind, reply.value).to_bytes(), bits.to_le_bytes());
    }

    /// Any frame decodes without panicking; feedback lies within the model's ranges and
    /// carries D0's nibbles.
    #[test]
    fn any_frame_decodes_without_panicking(
        model in any_model(), esc in 0u16..=0x4FE, id in 0u16..=0x7FF,
        data in proptest::collection::vec(any::<u8>(), 0..=8), extended: bool,
    ) {
        let r = model.ranges(RangeTable::Current);
        let frame = if extended {
            CanFrame::extended(u32::from(id), &data).unwrap()
        } else {
            CanFrame::standard(id, &data).unwrap()
        };
        match codec::decode_reply(&frame, esc, &r) {
            Some(Reply::Feedback(fb)) => {
                prop_assert!(!extended && data.len() == 8);
                prop_assert_eq!(fb.state.code(), data[0] >> 4);
                prop_assert_eq!(u16::from(fb.motor), esc & 0x0F);
                prop_assert!(fb.position_rad.abs() <= r.pmax);
                prop_assert!(fb.velocity_rad_s.abs() <= r.vmax);
                prop_assert!(fb.torque_nm.abs() <= r.tmax);
                prop_assert_eq!((fb.mos_temp_c, fb.rotor_temp_c), (data[6], data[7]));
            }
            Some(Reply::Register(reply)) => {
                prop_assert!(!extended && data.len() == 8);
                prop_assert!(reply.op == op::READ || reply.op == op::WRITE);
                prop_assert_eq!(u16::from_le_bytes([data[0], data[1]]), esc);
            }
            None => prop_assert!(
                extended || data.len() != 8 || u16::from(data[0] & 0x0F) != esc & 0x0F
            ),
        }
    }
}
