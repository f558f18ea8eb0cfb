//! The driver's codec against `fixtures/damiao/`: every host-to-motor vector is exactly the
//! frame the codec builds from the vector's fields, and every motor-to-host vector decodes to
//! its annotated values. A vector with a `cmd` the test does not know fails.

use bus::CanFrame;
use driver::damiao::codec::{self, op, special};
use driver::damiao::{
    ForcePosCommand, MitCommand, Model, RangeTable, Register, RegisterKind, RegisterValue, Reply,
    VelocityLen,
};
use testkit::fixtures::Vector;

use super::{f, ids, int, ranges, text, vectors, FILES};

/// The control mode a command belongs to (`None`: any mode).
fn mode_of(cmd: &str) -> Option<i64> {
    match cmd {
        "mit" => Some(1),
        "pos_vel" => Some(2),
        "velocity" => Some(3),
        "force_pos" => Some(4),
        _ => None,
    }
}

/// The reply the documented firmware gives to a host-to-motor vector.
fn expected_reply(v: &Vector) -> &'static str {
    let cmd = text(v, "cmd");
    match (cmd, mode_of(cmd)) {
        ("reg_read" | "reg_write", _) => "register",
        ("reg_save", _) => "none",
        (_, Some(mode)) if int(v, "ctrl_mode") != mode => "none",
        _ => "feedback",
    }
}

fn value_of(v: &Vector) -> RegisterValue {
    match text(v, "type") {
        "u32" => RegisterValue::U32(int(v, "value") as u32),
        "f32" => RegisterValue::F32(f(v, "value") as f32),
        other => panic!("{}: type {other}", v.name),
    }
}

/// The register a vector names, checked against its `rid` and `type`.
fn register_of(v: &Vector) -> Register {
    let register = Register::from_rid(int(v, "rid") as u8).expect("a named RID");
    assert_eq!(register.name(), text(v, "reg"), "{}", v.name);
    let kind = match register.kind() {
        RegisterKind::U32 => "u32",
        RegisterKind::F32 => "f32",
    };
    assert_eq!(kind, text(v, "type"), "{}", v.name);
    register
}

/// The frame the codec builds for a host-to-motor vector.
fn encode(v: &Vector) -> CanFrame {
    let (esc, _) = ids(v);
    let special_cmd = |code: u8| {
        assert_eq!(int(v, "code"), i64::from(code), "{}", v.name);
        codec::special(esc, code).unwrap()
    };
    match text(v, "cmd") {
        "enable" => special_cmd(special::ENABLE),
        "disable" => special_cmd(special::DISABLE),
        "set_zero" => special_cmd(special::SET_ZERO),
        "clear_error" => special_cmd(special::CLEAR_ERROR),
        "mit" => {
            let r = ranges(v);
            assert_eq!(
                (f(v, "pmax"), f(v, "vmax"), f(v, "tmax")),
                (f64::from(r.pmax), f64::from(r.vmax), f64::from(r.tmax)),
                "{}: the model table",
                v.name
            );
            let cmd = MitCommand {
                p_des_rad: f(v, "p_des_rad") as f32,
                v_des_rad_s: f(v, "v_des_rad_s") as f32,
                kp: f(v, "kp") as f32,
                kd: f(v, "kd") as f32,
                t_ff_nm: f(v, "t_ff_nm") as f32,
            };
            codec::mit(esc, &cmd, &r).unwrap()
        }
        "pos_vel" => {
            codec::pos_vel(esc, f(v, "p_des_rad") as f32, f(v, "v_des_rad_s") as f32).unwrap()
        }
        "velocity" => {
            let len = match int(v, "dlc") {
                4 => VelocityLen::Four,
                8 => VelocityLen::Eight,
                other => panic!("{}: dlc {other}", v.name),
            };
            codec::velocity(esc, f(v, "v_des_rad_s") as f32, len).unwrap()
        }
        "force_pos" => {
            let cmd = ForcePosCommand {
                p_des_rad: f(v, "p_des_rad") as f32,
                v_limit_rad_s: f(v, "v_des_rad_s") as f32,
                i_limit: f(v, "i_des") as f32,
            };
            codec::force_position(esc, &cmd).unwrap()
        }
        "reg_read" => codec::read_register(esc, register_of(v).rid()).unwrap(),
        "reg_write" => codec::write_register(esc, register_of(v).rid(), value_of(v)).unwrap(),
        "reg_save" => match int(v, "rid") {
            // The driver's own save.
            0 => codec::save(esc).unwrap(),
            // Another host's save: the same frame but for the ignored RID byte.
            rid => codec::register_frame(esc, op::SAVE, rid as u8, [0; 4]).unwrap(),
        },
        "refresh" => codec::refresh(esc).unwrap(),
        other => panic!("{}: no check for cmd={other}", v.name),
    }
}

#[test]
fn the_folder_holds_exactly_the_known_files() {
    let dir = testkit::fixtures::repo_path("damiao");
    let files: Vec<String> = testkit::fixtures::list_dir(dir)
        .unwrap()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files, FILES);
}

#[test]
fn every_command_vector_is_the_frame_the_codec_builds() {
    let all = vectors();
    let mut count = 0;
    for v in all.values().filter(|v| text(v, "dir") == "h2m") {
        assert_eq!(encode(v), v.frame, "{}", v.name);
        assert_eq!(text(v, "reply"), expected_reply(v), "{}", v.name);
        count += 1;
    }
    assert_eq!(count, 41, "host-to-motor vectors");
}

#[test]
fn every_motor_vector_decodes_to_its_fields() {
    let all = vectors();
    let (mut feedback, mut registers) = (0, 0);
    for v in all.values().filter(|v| text(v, "dir") == "m2h") {
        let (esc, mst) = ids(v);
        assert_eq!(v.frame.raw_id(), u32::from(mst), "{}: on MST_ID", v.name);
        let decoded = codec::decode_reply(&v.frame, esc, &ranges(v));
        match text(v, "cmd") {
            "feedback" => {
                let Some(Reply::Feedback(fb)) = decoded else {
                    panic!("{}: not feedback: {decoded:?}", v.name);
                };
                let tol = f(v, "tol");
                assert_eq!(i64::from(fb.state.code()), int(v, "state"), "{}", v.name);
                assert_eq!(fb.state.name(), text(v, "state_name"), "{}", v.name);
                assert_eq!(i64::from(fb.motor), int(v, "motor"), "{}", v.name);
                for (got, key) in [
                    (fb.position_rad, "pos_rad"),
                    (fb.velocity_rad_s, "vel_rad_s"),
                    (fb.torque_nm, "torque_nm"),
                ] {
                    let want = f(v, key);
                    assert!(
                        (f64::from(got) - want).abs() <= tol,
                        "{}: {key} {got} vs {want}",
                        v.name
                    );
                }
                assert_eq!(i64::from(fb.mos_temp_c), int(v, "t_mos_c"), "{}", v.name);
                assert_eq!(
                    i64::from(fb.rotor_temp_c),
                    int(v, "t_rotor_c"),
                    "{}",
                    v.name
                );
                feedback += 1;
            }
            "reg_reply" => {
                let Some(Reply::Register(reply)) = decoded else {
                    panic!("{}: not a register reply: {decoded:?}", v.name);
                };
                let register = register_of(v);
                assert_eq!(i64::from(reply.op), int(v, "op"), "{}", v.name);
                assert_eq!(reply.rid, register.rid(), "{}", v.name);
                assert_eq!(reply.esc_id, esc, "{}", v.name);
                assert_eq!(
                    RegisterValue::from_bytes(register.kind(), reply.value),
                    value_of(v),
                    "{}",
                    v.name
                );
                registers += 1;
            }
            other => panic!("{}: no check for cmd={other}", v.name),
        }
    }
    assert_eq!((feedback, registers), (12, 13));
}

#[test]
fn every_register_request_has_its_reply_and_every_reply_a_request() {
    let all = vectors();
    for v in all.values() {
        let cmd = text(v, "cmd");
        if cmd == "reg_read" || cmd == "reg_write" {
            let reply = &all[&format!("{}_reply", v.name)];
            // The reply repeats the request's ESC_ID, operation and RID.
            assert_eq!(reply.frame.data()[..4], v.frame.data()[..4], "{}", v.name);
            if cmd == "reg_write" {
                assert_eq!(reply.frame.data(), v.frame.data(), "{}: an echo", v.name);
            }
        }
        if cmd == "reg_reply" {
            let request = v
                .name
                .strip_suffix("_reply")
                .expect("named <request>_reply");
            assert!(all.contains_key(request), "{}", v.name);
        }
    }
}

#[test]
fn the_legacy_dm4340_table_and_wrong_ids_give_other_frames() {
    let all = vectors();
    // The DM4340 vector pins VMAX 10: the older table's 8 encodes v otherwise.
    let v = &all["mit_dm4340"];
    let legacy = Model::DM4340.ranges(RangeTable::Legacy);
    let cmd = MitCommand {
        p_des_rad: f(v, "p_des_rad") as f32,
        v_des_rad_s: f(v, "v_des_rad_s") as f32,
        kp: f(v, "kp") as f32,
        kd: f(v, "kd") as f32,
        t_ff_nm: f(v, "t_ff_nm") as f32,
    };
    assert_ne!(codec::mit(0x03, &cmd, &legacy).unwrap(), v.frame);
    let fb = &all["fb_dm4340"];
    let Some(Reply::Feedback(old)) = codec::decode_reply(&fb.frame, 0x03, &legacy) else {
        panic!("fb_dm4340");
    };
    assert!((f64::from(old.velocity_rad_s) - f(fb, "vel_rad_s")).abs() > 1.0);
    // Feedback decoded for the motor with another ESC_ID nibble is not ours.
    let enabled = &all["fb_enabled"];
    assert_eq!(
        codec::decode_reply(&enabled.frame, 0x02, &ranges(enabled)),
        None
    );
    // A register reply names its motor in D0..D1: another ESC_ID does not take it.
    let reply = &all["reg_read_ctrl_mode_reply"];
    assert!(!matches!(
        codec::decode_reply(&reply.frame, 0x101, &ranges(reply)),
        Some(Reply::Register(_))
    ));
}
