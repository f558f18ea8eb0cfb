//! Piper: the emulator's firmware state machine and the driver's feedback decoder.

use driver::piper::codec::{self as dcodec, FirmwareAssembler, MitPacking, MitRaw};
use sim::piper::{ids, Firmware, FirmwareProfile, PiperConfig, PiperSimState};

use super::input::{assert_finite, extended, standard, Input};

/// Most simulated milliseconds one input may run (keeps one execution short: the physics
/// dominates the cost).
const MAX_TICKS: u32 = 300;

/// Identifiers the master controller listens to, so most generated frames reach a handler.
const HOST_IDS: &[u16] = &[
    ids::LED,
    ids::MOTION_CTRL_1,
    ids::MODE_CTRL,
    ids::END_POSE_XY,
    ids::END_POSE_ZRX,
    ids::END_POSE_RYRZ,
    ids::JOINT_12,
    ids::JOINT_34,
    ids::JOINT_56,
    ids::MOVE_C_POINT,
    ids::GRIPPER_CTRL,
    0x15A,
    0x15B,
    0x15C,
    0x15D,
    0x15E,
    0x15F,
    0x181,
    0x183,
    0x187,
    ids::LEADER_HOME,
    ids::UPGRADE_MODE,
    ids::LINKAGE_CONFIG,
    ids::MOTOR_ENABLE,
    ids::JOINT_QUERY,
    ids::SET_JOINT_LIMITS,
    ids::JOINT_CONFIG,
    ids::PARAM_QUERY,
    ids::SET_END_VEL_ACC,
    ids::SET_COLLISION,
    ids::SET_GRIPPER_TEACH,
    ids::SET_ASSIST,
    ids::FIRMWARE,
];

/// Frames and 1 ms ticks into a freshly booted Piper firmware.
///
/// Input: byte 0 picks the firmware profile; then operations: a tag byte (`% 4 == 0`: run
/// `1..=16` ticks given by the next byte; otherwise one frame: an id selector byte — mostly a
/// host command id, sometimes a raw 11-bit or 29-bit id — a length byte and the payload).
///
/// Asserts: no panic; every emitted frame is an 11-bit frame the driver's decoder accepts
/// (while no ID offsets are configured, since the driver then expects shifted ids); the
/// simulated state (joints, speeds, torques, currents, temperatures, gripper, flange pose)
/// stays finite.
pub fn piper_emulator(data: &[u8]) {
    let mut input = Input::new(data);
    let profile = FirmwareProfile::ALL[usize::from(input.byte().unwrap_or(0)) % 4];
    let mut fw = Firmware::new(PiperConfig {
        firmware: profile,
        ..PiperConfig::default()
    })
    .expect("the default configuration boots");
    let mut ticks = 0u32;
    // The driver decodes the firmware's ids only while no ID offset is configured; offsets are
    // set through 0x470 alone, so stop checking ids once such a frame went in (cheaper than a
    // snapshot of the flash after every frame).
    let mut offsets_default = true;
    while !input.is_empty() && ticks < MAX_TICKS {
        let tag = input.byte().unwrap_or(0);
        if tag.is_multiple_of(4) {
            let n = u32::from(input.byte().unwrap_or(0) % 16) + 1;
            for _ in 0..n {
                fw.tick();
            }
            ticks += n;
            check_state(&fw.snapshot());
        } else {
            let frame = host_frame(&mut input);
            offsets_default &=
                frame.is_extended() || frame.raw_id() != u32::from(ids::LINKAGE_CONFIG);
            fw.handle_frame(&frame);
        }
        for frame in fw.take_output() {
            check_emitted(&frame, offsets_default);
        }
    }
}

fn host_frame(input: &mut Input<'_>) -> bus::CanFrame {
    let sel = input.byte().unwrap_or(0);
    if sel < 0xE0 {
        let id = HOST_IDS[usize::from(sel) % HOST_IDS.len()];
        standard(id, &input.payload())
    } else if sel < 0xF8 {
        let id = input.u16();
        standard(id, &input.payload())
    } else {
        let id = input.u32();
        extended(id, &input.payload())
    }
}

fn check_emitted(frame: &bus::CanFrame, check_ids: bool) {
    assert!(
        !frame.is_extended(),
        "the Piper firmware sent an extended frame: {frame}"
    );
    if check_ids {
        if let Err(e) = dcodec::decode(frame) {
            panic!("the driver cannot decode emulator frame {frame}: {e}");
        }
    }
}

fn check_state(s: &PiperSimState) {
    assert_finite("joint_positions_rad", &s.joint_positions_rad);
    assert_finite("reported_joints_rad", &s.reported_joints_rad);
    assert_finite("joint_velocities_rad_s", &s.joint_velocities_rad_s);
    assert_finite("joint_torques_nm", &s.joint_torques_nm);
    assert_finite("motor_currents_a", &s.motor_currents_a);
    assert_finite("motor_temps_c", &s.motor_temps_c);
    assert_finite("gripper", &[s.gripper_stroke_m, s.gripper_force_n]);
}

/// Arbitrary frames into the driver's Piper decoder, its MIT decoder and its firmware-reply
/// assembler.
///
/// Input: repeated (id selector byte, length byte, payload); the selector picks a feedback or
/// reply id most of the time, else a raw 11-bit id, else an extended id.
///
/// Asserts: no panic; whatever decodes converts to finite SI values; an MIT frame that
/// decodes re-encodes to the same bytes (decode is the inverse of encode on its image).
pub fn piper_driver_decode(data: &[u8]) {
    let mut input = Input::new(data);
    let mut assembler = FirmwareAssembler::new();
    while !input.is_empty() {
        let sel = input.byte().unwrap_or(0);
        let frame = if sel < 0xC0 {
            // 0x151..=0x15F control echoes and MIT, 0x181.. replies, 0x251.. feedback, 0x2A1..,
            // 0x47x replies, 0x481.. and the firmware reply.
            let base: &[u16] = &[0x150, 0x180, 0x250, 0x260, 0x2A0, 0x470, 0x480, 0x4AF];
            let id = base[usize::from(sel) % base.len()] + u16::from(sel / 8 % 16);
            standard(id, &input.payload())
        } else if sel < 0xF0 {
            let id = input.u16();
            standard(id, &input.payload())
        } else {
            let id = input.u32();
            extended(id, &input.payload())
        };
        match dcodec::decode(&frame) {
            Ok(Some(dcodec::Message::FirmwarePart(part))) => {
                if let Some(info) = assembler.push(&part) {
                    let _ = format!("{info:?}");
                }
            }
            Ok(Some(message)) => check_message(&message),
            Ok(None) | Err(_) => {}
        }
        decode_each(&frame);
        for packing in [MitPacking::Torque8Crc, MitPacking::Torque12] {
            if let Ok((joint, raw)) = MitRaw::decode(&frame, packing) {
                let si = raw.to_si(packing);
                assert_finite("mit", &[si.p_rad, si.v_rad_s, si.kp, si.kd, si.t_nm]);
                let again = raw.encode(joint, packing);
                assert_eq!(again, frame, "MIT decode → encode changed the frame");
            }
        }
    }
}

/// Every public per-message decoder on any frame (callers may hand them frames the dispatcher
/// would not): errors are fine, panics are not.
fn decode_each(frame: &bus::CanFrame) {
    let _ = format!(
        "{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}{:?}",
        dcodec::ArmStatus::decode(frame),
        dcodec::EndPosePart::decode(frame),
        dcodec::JointPair::decode_feedback(frame),
        dcodec::JointPair::decode_command(frame),
        dcodec::GripperFeedback::decode(frame),
        dcodec::HighSpeedFeedback::decode(frame),
        dcodec::LowSpeedFeedback::decode(frame),
        dcodec::EndVelAccFeedback::decode(frame),
        dcodec::JointLimits::decode(frame),
        dcodec::JointMaxAcc::decode(frame),
        dcodec::Ack::decode(frame),
        dcodec::EndParams::decode(frame),
        dcodec::CollisionLevels::decode(frame),
        dcodec::GripperTeachParams::decode(frame),
        dcodec::AssistLevels::decode(frame),
        dcodec::FirmwarePart::decode(frame),
        dcodec::CpvFrame::decode(frame),
        dcodec::ModeCtrl::decode(frame),
        dcodec::GripperCtrl::decode(frame),
    );
}

/// Every message the driver decodes must turn into finite SI values.
fn check_message(message: &dcodec::Message) {
    use dcodec::Message;
    match message {
        Message::HighSpeed(h) => assert!(h.effort_mnm().is_finite()),
        Message::Joints(p) | Message::JointCmdEcho(p) => assert_finite(
            "joint pair",
            &[dcodec::mdeg_to_rad(p.a_mdeg), dcodec::mdeg_to_rad(p.b_mdeg)],
        ),
        _ => {}
    }
    // Serialising walks every field (the driver records messages this way).
    serde_json::to_string(message).expect("a decoded message serialises");
}
