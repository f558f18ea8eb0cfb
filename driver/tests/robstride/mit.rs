//! The driver's MIT codec against `fixtures/robstride/mit.log`: every command vector is the
//! exact frame the codec builds from the vector's fields, and every motor-to-host vector decodes
//! to its annotated fields.

use std::collections::BTreeMap;

use bus::CanFrame;
use driver::robstride::mit_codec::{self, kind, marker, MitIncoming, NO_ARG};
use driver::robstride::{Model, MotorMode, OpControl, ParamValue, RangeTable};
use testkit::fixtures::Vector;

fn vectors() -> BTreeMap<String, Vector> {
    let path = testkit::fixtures::repo_path("robstride").join("mit.log");
    let mut out = BTreeMap::new();
    for v in testkit::fixtures::read_file(path).unwrap_or_else(|e| panic!("{e}")) {
        if let Some(old) = out.insert(v.name.clone(), v) {
            panic!("{}: vector name {} used twice", old.at, old.name);
        }
    }
    out
}

fn f(v: &Vector, key: &str) -> f64 {
    v.float(key).unwrap_or_else(|e| panic!("{e}"))
}

fn int(v: &Vector, key: &str) -> i64 {
    v.int(key).unwrap_or_else(|e| panic!("{e}"))
}

/// The frame the codec builds for a host-to-motor vector.
fn encode(v: &Vector) -> CanFrame {
    let motor = int(v, "motor") as u8;
    let r = Model::RS03.ranges(RangeTable::Manual);
    let cmd = |f_cmd: u8, mark: u8| mit_codec::command(motor, f_cmd, mark).unwrap();
    match int(v, "cmd") {
        1 => cmd(NO_ARG, marker::ENABLE_OR_MODE),
        2 => cmd(NO_ARG, marker::STOP_OR_PROTOCOL),
        3 => {
            let setpoint = OpControl {
                angle_rad: f(v, "angle_rad") as f32,
                speed_rad_s: f(v, "speed_rad_s") as f32,
                kp: f(v, "kp") as f32,
                kd: f(v, "kd") as f32,
                torque_nm: f(v, "torque_nm") as f32,
            };
            mit_codec::setpoint(motor, &setpoint, &r).unwrap()
        }
        4 => cmd(NO_ARG, marker::ZERO),
        5 => cmd(int(v, "f_cmd") as u8, marker::FAULT),
        6 => cmd(int(v, "mode") as u8, marker::ENABLE_OR_MODE),
        7 => cmd(int(v, "new_id") as u8, marker::CAN_ID),
        8 => cmd(int(v, "protocol") as u8, marker::STOP_OR_PROTOCOL),
        9 => cmd(int(v, "host") as u8, marker::HOST_ID),
        10 => mit_codec::f32_pair(
            kind::POSITION,
            motor,
            f(v, "angle_rad") as f32,
            f(v, "speed_rad_s") as f32,
        )
        .unwrap(),
        11 => mit_codec::f32_pair(
            kind::VELOCITY,
            motor,
            f(v, "speed_rad_s") as f32,
            f(v, "current_a") as f32,
        )
        .unwrap(),
        12 => cmd(NO_ARG, marker::SAVE),
        13 => cmd(int(v, "enable") as u8, marker::REPORT),
        14 => mit_codec::read_param(motor, int(v, "index") as u16).unwrap(),
        15 => mit_codec::write_param(
            motor,
            int(v, "index") as u16,
            ParamValue::F32(f(v, "value") as f32),
        )
        .unwrap(),
        other => panic!("{}: command {other}", v.name),
    }
}

#[test]
fn every_command_vector_is_the_frame_the_codec_builds() {
    let all = vectors();
    let mut count = 0;
    for v in all.values().filter(|v| v.fields["dir"] == "h2m") {
        assert_eq!(encode(v), v.frame, "{}", v.name);
        count += 1;
    }
    assert!(count >= 19, "{count} command vectors");
}

#[test]
fn motor_vectors_decode_to_their_fields() {
    let all = vectors();
    let r = Model::RS03.ranges(RangeTable::Manual);
    for name in ["mit_resp1_run", "mit_resp1_fault"] {
        let v = &all[name];
        let Some(MitIncoming::Status(s)) = mit_codec::decode(&v.frame, 0xFD, |_| Some(r)) else {
            panic!("{name}: not a Response 1");
        };
        let tol = f(v, "tol") as f32;
        assert_eq!(i64::from(s.motor_id), int(v, "motor"));
        let state = match s.mode {
            MotorMode::Reset => 0,
            MotorMode::Calibration => 1,
            MotorMode::Run => 2,
            MotorMode::Brake => 3,
        };
        assert_eq!(state, int(v, "state"), "{name}");
        assert_eq!(i64::from(s.fault), int(v, "fault"), "{name}");
        assert_eq!(i64::from(s.warning), int(v, "warning"), "{name}");
        assert!(
            (s.angle_rad - f(v, "angle_rad") as f32).abs() <= tol,
            "{s:?}"
        );
        assert!(
            (s.speed_rad_s - f(v, "speed_rad_s") as f32).abs() <= tol,
            "{s:?}"
        );
        assert!(
            (s.torque_nm - f(v, "torque_nm") as f32).abs() <= tol,
            "{s:?}"
        );
        assert!(
            (s.temperature_c - f(v, "temp_c") as f32).abs() < 0.01,
            "{s:?}"
        );
    }
    let v = &all["mit_fault_reply"];
    assert_eq!(
        mit_codec::decode(&v.frame, 0xFD, |_| Some(r)),
        Some(MitIncoming::FaultWord {
            motor_id: 0x7F,
            word: int(v, "fault_word") as u32
        })
    );
    let v = &all["mit_resp2"];
    let Some(MitIncoming::Uid { motor_id, uid }) = mit_codec::decode(&v.frame, 0xFD, |_| None)
    else {
        panic!("mit_resp2");
    };
    assert_eq!(motor_id, 0x7F);
    assert_eq!(u64::from_le_bytes(uid) as i64, int(v, "uid"));
    for (name, write) in [
        ("mit_read_loc_kp_reply", false),
        ("mit_write_limit_spd_reply", true),
    ] {
        let v = &all[name];
        let Some(MitIncoming::Param {
            motor_id,
            write: w,
            index,
            value,
        }) = mit_codec::decode(&v.frame, 0xFD, |_| None)
        else {
            panic!("{name}");
        };
        assert_eq!((motor_id, w), (0x7F, write), "{name}");
        assert_eq!(i64::from(index), int(v, "index"));
        assert_eq!(f64::from(f32::from_le_bytes(value)), f(v, "value"));
    }
    // Frames of the private protocol are not MIT frames.
    let private = CanFrame::extended(0x0280_7FFD, &[0; 8]).unwrap();
    assert_eq!(mit_codec::decode(&private, 0xFD, |_| Some(r)), None);
}
