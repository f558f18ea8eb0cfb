//! Property tests of the driver's own codecs: every message type the driver both encodes and
//! decodes survives encode → decode unchanged, across the full range of every field.

use bus::CanFrame;
use driver::piper::codec::{
    self as piper, ArmStatus, AssistLevels, CollisionLevels, CpvFrame, EndParams, EndPosePart,
    EndPoseTarget, GripperCtrl, GripperTeachParams, JointLimits, JointPair, JointTargets,
    MitPacking, MitRaw, ModeCtrl,
};
use driver::robstride::codec::{self as rs, Incoming};
use driver::robstride::{Model, RangeTable};
use proptest::prelude::*;

/// Decoding an arbitrary 8-byte payload on `id`, then encoding and decoding again, gives the
/// same message: so encode → decode is the identity on everything the decoder can produce.
fn decode_encode_decode<T: PartialEq + std::fmt::Debug>(
    id: u16,
    bytes: [u8; 8],
    decode: impl Fn(&CanFrame) -> Result<T, piper::DecodeError>,
    encode: impl Fn(&T) -> CanFrame,
) -> Result<(), TestCaseError> {
    let frame = CanFrame::standard(id, &bytes).unwrap();
    if let Ok(message) = decode(&frame) {
        let again = decode(&encode(&message));
        prop_assert_eq!(again, Ok(message));
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn piper_status_and_settings_round_trip(bytes in any::<[u8; 8]>()) {
        decode_encode_decode(0x2A1, bytes, ArmStatus::decode, ArmStatus::encode)?;
        decode_encode_decode(0x151, bytes, ModeCtrl::decode, ModeCtrl::encode)?;
        decode_encode_decode(0x159, bytes, GripperCtrl::decode, GripperCtrl::encode)?;
        decode_encode_decode(0x478, bytes, EndParams::decode, EndParams::encode_set)?;
        decode_encode_decode(0x47B, bytes, CollisionLevels::decode, CollisionLevels::encode_set)?;
        decode_encode_decode(0x488, bytes, AssistLevels::decode, AssistLevels::encode_set)?;
        decode_encode_decode(
            0x47E, bytes, GripperTeachParams::decode, GripperTeachParams::encode_set)?;
        decode_encode_decode(0x473, bytes, JointLimits::decode, JointLimits::encode_set)?;
    }

    #[test]
    fn piper_cpv_round_trips(motor in 1u8..=7, mode: u8, param: [u8; 2], value: i32) {
        let cpv = CpvFrame { motor, mode: mode.into(), param, value };
        prop_assert_eq!(CpvFrame::decode(&cpv.encode()), Ok(cpv));
    }

    #[test]
    fn piper_gripper_command_round_trips(
        stroke_um: i32, effort_mnm: u16, enable: bool, clear_error: bool, set_zero: bool,
    ) {
        let g = GripperCtrl { stroke_um, effort_mnm, enable, clear_error, set_zero };
        prop_assert_eq!(GripperCtrl::decode(&g.encode()), Ok(g));
    }

    #[test]
    fn piper_joint_and_pose_targets_round_trip(angles_mdeg: [i32; 6], pose: [i32; 6]) {
        let frames = JointTargets { angles_mdeg }.encode();
        for (k, f) in frames.iter().enumerate() {
            let pair = JointPair::decode_command(f).unwrap();
            prop_assert_eq!(pair.first_joint as usize, 2 * k + 1);
            prop_assert_eq!([pair.a_mdeg, pair.b_mdeg], [angles_mdeg[2 * k], angles_mdeg[2 * k + 1]]);
        }
        let target = EndPoseTarget {
            x_um: pose[0], y_um: pose[1], z_um: pose[2],
            rx_mdeg: pose[3], ry_mdeg: pose[4], rz_mdeg: pose[5],
        };
        let parts: Vec<_> = target.encode().iter().map(|f| EndPosePart::decode(f).unwrap()).collect();
        prop_assert_eq!(parts, vec![
            EndPosePart::Xy { x_um: pose[0], y_um: pose[1] },
            EndPosePart::ZRx { z_um: pose[2], rx_mdeg: pose[3] },
            EndPosePart::RyRz { ry_mdeg: pose[4], rz_mdeg: pose[5] },
        ]);
    }

    #[test]
    fn piper_mit_round_trips_with_both_packings(
        joint in 1u8..=6, p: u16, v in 0u16..0x1000, kp in 0u16..0x1000, kd in 0u16..0x1000,
        t in 0u16..0x1000,
    ) {
        for (packing, t) in [(MitPacking::Torque8Crc, t & 0xFF), (MitPacking::Torque12, t)] {
            let raw = MitRaw { p, v, kp, kd, t };
            prop_assert_eq!(MitRaw::decode(&raw.encode(joint, packing), packing), Ok((joint, raw)));
        }
    }

    /// Wire → SI → wire is exact up to one step (the protocol truncates, as the manual says),
    /// and SI values outside the range saturate at its ends.
    #[test]
    fn robstride_scaling_round_trips_and_saturates(raw: u16, model_index in 0usize..8, x in -1e6f32..1e6) {
        let model = Model::parse(["RS00", "RS01", "RS02", "RS03", "RS04", "RS05", "RS06", "EL05"][model_index]).unwrap();
        let r = model.ranges(RangeTable::Manual);
        for max in [r.angle_rad, r.speed_rad_s, r.torque_nm] {
            let back = rs::to_u16(rs::from_u16(raw, -max, max), -max, max);
            prop_assert!(back.abs_diff(raw) <= 1, "{raw} → {back} over ±{max}");
            let wire = rs::to_u16(x, -max, max);
            if x >= max { prop_assert_eq!(wire, u16::MAX); }
            if x <= -max { prop_assert_eq!(wire, 0); }
            let si = rs::from_u16(wire, -max, max);
            prop_assert!(si.abs() <= max * (1.0 + 1e-6));
            prop_assert!((si - x.clamp(-max, max)).abs() <= 2.0 * max / 65535.0 * 1.01);
        }
    }

    #[test]
    fn robstride_param_replies_and_ids_round_trip(comm in 0u8..32, data2: u16, dst: u8, index: u16, value: [u8; 4]) {
        let id = rs::ext_id(comm, data2, dst);
        prop_assert_eq!(((id >> 24) as u8, ((id >> 8) & 0xFFFF) as u16, id as u8), (comm, data2, dst));
        let [i0, i1] = index.to_le_bytes();
        let frame = rs::request(17, u16::from(dst.wrapping_add(1)) , 0xFD, [i0, i1, 0, 0, value[0], value[1], value[2], value[3]]).unwrap();
        // A type-17 frame addressed to host 0xFD reads back as a parameter reply.
        let decoded = rs::decode(&frame, 0xFD, std::time::Duration::ZERO, |_| None);
        prop_assert_eq!(decoded, Some(Incoming::Param { motor_id: dst.wrapping_add(1), ok: true, index, value }));
    }
}
