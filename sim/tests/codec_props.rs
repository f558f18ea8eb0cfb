//! Property tests of the emulator's own codecs: encode → decode is the identity for every
//! message type the emulator both encodes and decodes, across the full range of every field,
//! and scaled values saturate at the ends of their range instead of wrapping.

use bus::CanFrame;
use proptest::prelude::*;
use sim::piper::codec::host::{self, HostCommand};
use sim::piper::codec::{arm, mit};
use sim::piper::profile::MitPacking;
use sim::piper::FirmwareProfile;
use sim::robstride::codec::{self as rs, ExtId};
use sim::robstride::{Model, RangeTable};

fn profile(index: usize) -> FirmwareProfile {
    FirmwareProfile::ALL[index % FirmwareProfile::ALL.len()]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// 0x151 and 0x159 are the host commands the emulator also encodes (a leader arm emits
    /// them): whatever decodes, encodes back to a frame that decodes to the same command.
    #[test]
    fn piper_mode_and_gripper_commands_round_trip(bytes: [u8; 8], p in 0usize..4) {
        let profile = profile(p);
        // Mostly valid enum bytes, so that most cases decode (and some do not).
        let mut m = bytes;
        m[0] %= 9;
        m[1] = if m[1] >= 0xF8 { 0xFF } else { m[1] % 8 };
        m[2] %= 128;
        m[3] = [0x00, host::MIT_FLAG, 0xFF, m[3]][usize::from(m[3] % 4)];
        m[5] %= 5;
        let mode = CanFrame::standard(0x151, &m).unwrap();
        if let Ok(HostCommand::ModeCtrl(m)) = host::decode(&mode, 0, profile) {
            let again = host::decode(&host::encode_mode_ctrl(0x151, &m, profile), 0, profile);
            prop_assert_eq!(again, Ok(HostCommand::ModeCtrl(m)));
        }
        let gripper = CanFrame::standard(0x159, &bytes).unwrap();
        if let Ok(HostCommand::Gripper(g)) = host::decode(&gripper, 0, profile) {
            let again = host::decode(&host::encode_gripper(0x159, &g), 0, profile);
            prop_assert_eq!(again, Ok(HostCommand::Gripper(g)));
        }
    }

    #[test]
    fn piper_mit_packing_round_trips(
        p: u16, v in 0u16..0x1000, kp in 0u16..0x1000, kd in 0u16..0x1000, t in 0u16..0x1000,
    ) {
        for (packing, t) in [(MitPacking::Torque8WithCheck, t & 0xFF), (MitPacking::Torque12, t)] {
            let raw = mit::MitRaw { p, v, kp, kd, t };
            prop_assert_eq!(mit::unpack(&mit::pack(raw, packing), packing), Ok(raw));
            // Wire → SI → wire: one step at most (the protocol truncates).
            let back = mit::MitRaw::from_command(&raw.to_command(packing), packing);
            for (a, b) in [(back.p, p), (back.v, v), (back.kp, kp), (back.kd, kd), (back.t, t)] {
                prop_assert!(a.abs_diff(b) <= 1, "{raw:?} → {back:?}");
            }
        }
    }

    /// SI → wire saturates at the field's ends (never wraps), whatever the value.
    #[test]
    fn piper_scaled_fields_saturate(x in prop::num::f64::ANY) {
        let i32_wire = arm::sat_i32(x);
        let i16_wire = arm::sat_i16(x);
        let u16_wire = arm::sat_u16(x);
        if x.is_nan() {
            prop_assert_eq!((i32_wire, i16_wire, u16_wire), (0, 0, 0));
            return Ok(());
        }
        let near = |wire: f64, lo: f64, hi: f64| (wire - x.clamp(lo, hi)).abs() < 1.0;
        prop_assert!(near(f64::from(i32_wire), f64::from(i32::MIN), f64::from(i32::MAX)));
        prop_assert!(near(f64::from(i16_wire), -32768.0, 32767.0));
        prop_assert!(near(f64::from(u16_wire), 0.0, 65535.0));
        for (bits, range) in [(16, mit::P_RANGE_RAD), (12, mit::V_RANGE_RAD_S), (8, mit::T8_RANGE_NM)] {
            let wire = mit::quantise(x, bits, range);
            prop_assert!(u32::from(wire) < (1 << bits));
            if x >= range.1 { prop_assert_eq!(u32::from(wire), (1 << bits) - 1); }
            if x <= range.0 { prop_assert_eq!(wire, 0); }
        }
    }

    #[test]
    fn robstride_ids_round_trip(raw in 0u32..(1 << 29)) {
        prop_assert_eq!(ExtId::parse(raw).raw(), raw);
    }

    #[test]
    fn robstride_scaling_round_trips_and_saturates(
        raw: u16, model in 0usize..8, x in prop::num::f32::ANY,
    ) {
        let r = Model::ALL[model].ranges(RangeTable::Manual);
        for max in [r.angle_rad, r.speed_rad_s, r.torque_nm] {
            let back = rs::float_to_u16(rs::u16_to_float(raw, -max, max), -max, max);
            prop_assert!(back.abs_diff(raw) <= 1, "{raw} → {back} over ±{max}");
            let wire = rs::float_to_u16(x, -max, max);
            if x >= max { prop_assert_eq!(wire, u16::MAX); }
            if x <= -max { prop_assert_eq!(wire, 0); }
        }
        let status = rs::status_payload(x, x, x, x, &r);
        if x >= r.angle_rad.max(r.speed_rad_s).max(r.torque_nm) {
            prop_assert_eq!(&status[..6], &[0xFF; 6]);
        }
        if x <= -r.angle_rad.max(r.speed_rad_s).max(r.torque_nm) {
            prop_assert_eq!(&status[..6], &[0; 6]);
        }
    }
}
