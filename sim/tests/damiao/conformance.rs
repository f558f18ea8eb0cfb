//! Conformance against the shared fixtures (`fixtures/damiao/`, written by
//! `make_vectors.py` from the protocol note, independent of this codec): every host-to-motor
//! vector of `commands.log` and `registers.log` is fed to a motor in the vector's mode and
//! gets the documented reply (a feedback frame with its state, a register reply byte for
//! byte, or nothing); the emulator's codec packs the annotated MIT values into the vector's
//! bytes; every feedback vector decodes to its annotated values.

use std::collections::BTreeMap;

use bus::CanFrame;
use sim::damiao::codec::{Feedback, MitCommand, PosForceCommand, PosVelCommand};
use sim::damiao::registers::rid;
use sim::damiao::{DamiaoMotor, Model, MotorConfig};
use testkit::fixtures::Vector;

use super::{decode, one, write};

/// Every vector of one fixture file, by name; a missing file or a repeated name fails.
fn load(file: &str) -> BTreeMap<String, Vector> {
    let path = testkit::fixtures::repo_path("damiao").join(file);
    let mut out = BTreeMap::new();
    for v in testkit::fixtures::read_file(&path).unwrap_or_else(|e| panic!("{e}")) {
        if let Some(old) = out.insert(v.name.clone(), v) {
            panic!("{}: vector name {} used twice", old.at, old.name);
        }
    }
    assert!(!out.is_empty(), "{file} has no vectors");
    out
}

fn int(v: &Vector, key: &str) -> i64 {
    v.int(key).unwrap_or_else(|e| panic!("{e}"))
}

fn real(v: &Vector, key: &str) -> f64 {
    v.float(key).unwrap_or_else(|e| panic!("{e}"))
}

fn model(v: &Vector) -> Model {
    Model::named(v.text("model").unwrap_or_else(|e| panic!("{e}")))
        .unwrap_or_else(|e| panic!("{v}: {e}"))
}

/// A disabled motor with the vector's model and ids, in its `ctrl_mode` if it names one.
fn motor_for(v: &Vector) -> DamiaoMotor {
    let esc = u16::try_from(int(v, "esc_id")).unwrap();
    let mst = u16::try_from(int(v, "mst_id")).unwrap();
    let mut m = DamiaoMotor::new(MotorConfig::new(esc, model(v)).with_mst_id(mst));
    if v.has("ctrl_mode") {
        let mode = u32::try_from(int(v, "ctrl_mode")).unwrap();
        one(write(&mut m, rid::CTRL_MODE, mode.to_le_bytes()));
    }
    m
}

/// Feed `v` to `m` and check the reply its `reply` field documents.
fn check_reply(v: &Vector, m: &mut DamiaoMotor) -> Vec<CanFrame> {
    let replies = m.handle_frame(&v.frame);
    match v.text("reply").unwrap_or_else(|e| panic!("{e}")) {
        "none" => assert!(
            replies.is_empty(),
            "{v}: expected no reply, got {replies:?}"
        ),
        "feedback" => {
            assert_eq!(replies.len(), 1, "{v}: {replies:?}");
            let fb = decode(m, replies[0]);
            if v.has("reply_state") {
                assert_eq!(i64::from(fb.state), int(v, "reply_state"), "{v}");
            }
        }
        "register" => {
            assert_eq!(replies.len(), 1, "{v}: {replies:?}");
            let reply = replies[0];
            assert_eq!(reply.raw_id(), u32::from(m.mst_id()), "{v}");
            assert_eq!(reply.data()[..4], v.frame.data()[..4], "{v}: {reply}");
        }
        other => panic!("{v}: unknown reply kind {other}"),
    }
    replies
}

#[test]
fn every_command_vector_gets_its_documented_reply() {
    let all = load("commands.log");
    let mut seen = 0;
    for v in all.values().filter(|v| v.text("dir").ok() == Some("h2m")) {
        let mut m = motor_for(v);
        check_reply(v, &mut m);
        seen += 1;
    }
    assert!(seen >= 20, "only {seen} command vectors");
}

#[test]
fn the_codec_packs_the_annotated_values_into_the_vector_s_bytes() {
    let all = load("commands.log");
    for v in all.values() {
        match v.text("cmd").unwrap_or_default() {
            "mit" => {
                let ranges = model(v).ranges();
                assert_eq!(f64::from(ranges.v_max_rad_s), real(v, "vmax"), "{v}");
                assert_eq!(f64::from(ranges.t_max_nm), real(v, "tmax"), "{v}");
                let command = MitCommand {
                    p_des_rad: real(v, "p_des_rad"),
                    v_des_rad_s: real(v, "v_des_rad_s"),
                    kp_nm_per_rad: real(v, "kp"),
                    kd_nm_s_per_rad: real(v, "kd"),
                    t_ff_nm: real(v, "t_ff_nm"),
                };
                assert_eq!(command.pack(&ranges), v.frame.data(), "{v}");
                // Unpacked, each field is within one step of the annotation (clamped).
                let data: [u8; 8] = v.frame.data().try_into().unwrap();
                let back = MitCommand::unpack(&data, &ranges);
                let p = f64::from(ranges.p_max_rad);
                let within = |x: f64, want: f64, span: f64, steps: f64| {
                    (x - want).abs() <= span / steps + 1e-9
                };
                assert!(
                    within(
                        back.p_des_rad,
                        command.p_des_rad.clamp(-p, p),
                        2.0 * p,
                        65535.0
                    ),
                    "{v}"
                );
                assert!(
                    within(
                        back.kp_nm_per_rad,
                        command.kp_nm_per_rad.clamp(0.0, 500.0),
                        500.0,
                        4095.0
                    ),
                    "{v}"
                );
            }
            "pos_vel" => {
                let command = PosVelCommand::parse(v.frame.data()).unwrap();
                assert_eq!(f64::from(command.p_des_rad), real(v, "p_des_rad"), "{v}");
                assert_eq!(
                    f64::from(command.v_des_rad_s),
                    real(v, "v_des_rad_s"),
                    "{v}"
                );
            }
            "velocity" => {
                assert_eq!(v.frame.len() as i64, int(v, "dlc"), "{v}");
            }
            "force_pos" => {
                let command = PosForceCommand::parse(v.frame.data()).unwrap();
                assert_eq!(f64::from(command.p_des_rad), real(v, "p_des_rad"), "{v}");
                let v_limit = real(v, "v_des_rad_s").min(100.0);
                assert_eq!(command.v_des_rad_s, v_limit, "{v}");
                assert_eq!(command.current_fraction, real(v, "i_des").min(1.0), "{v}");
            }
            _ => {}
        }
    }
}

#[test]
fn every_register_vector_gets_its_documented_reply_byte_for_byte() {
    let all = load("registers.log");
    let mut compared = 0;
    for v in all.values().filter(|v| v.text("dir").ok() == Some("h2m")) {
        let mut m = motor_for(v);
        let expected = all.get(&format!("{}_reply", v.name));
        // A read's example value is set first (every register the vectors read is RW).
        if let (Some(reply), "reg_read") = (expected, v.text("cmd").unwrap_or_default()) {
            let rid = u8::try_from(int(v, "rid")).unwrap();
            let value: [u8; 4] = reply.frame.data()[4..8].try_into().unwrap();
            one(write(&mut m, rid, value));
        }
        let replies = check_reply(v, &mut m);
        if let Some(reply) = expected {
            assert_eq!(replies, [reply.frame], "{v}");
            compared += 1;
        }
        if v.text("cmd").ok() == Some("reg_save") {
            assert!(m.take_persist_request(), "{v}: a save asks for a persist");
        }
    }
    assert!(compared >= 10, "only {compared} replies compared");
}

#[test]
fn every_feedback_vector_decodes_to_its_annotated_values() {
    let all = load("feedback.log");
    for v in all.values() {
        let ranges = model(v).ranges();
        let data: [u8; 8] = v.frame.data().try_into().unwrap();
        let fb = Feedback::unpack(&data, &ranges);
        let tol = real(v, "tol");
        assert_eq!(i64::from(fb.state), int(v, "state"), "{v}");
        assert_eq!(i64::from(fb.id_nibble), int(v, "motor"), "{v}");
        assert_eq!(v.raw_id() as i64, int(v, "mst_id"), "{v}");
        assert!(
            (fb.position_rad - real(v, "pos_rad")).abs() <= tol,
            "{v}: {fb:?}"
        );
        assert!(
            (fb.velocity_rad_s - real(v, "vel_rad_s")).abs() <= tol,
            "{v}: {fb:?}"
        );
        assert!(
            (fb.torque_nm - real(v, "torque_nm")).abs() <= tol,
            "{v}: {fb:?}"
        );
        assert_eq!(i64::from(fb.mos_temp_c), int(v, "t_mos_c"), "{v}");
        assert_eq!(i64::from(fb.rotor_temp_c), int(v, "t_rotor_c"), "{v}");
    }
}

#[test]
fn a_motor_at_rest_sends_the_disabled_feedback_vector_exactly() {
    let all = load("feedback.log");
    let v = &all["fb_disabled"];
    let mut m = motor_for(v);
    m.set_mos_temperature(real(v, "t_mos_c"));
    m.set_coil_temperature(real(v, "t_rotor_c"));
    let refresh = CanFrame::standard(0x7FF, &[0x01, 0x00, 0xCC, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(m.handle_frame(&refresh), [v.frame]);
}
