//! Emulator conformance against the shared fixtures (`fixtures/robstride/`: the worked examples
//! and the reply matrix of docs/protocols/robstride.md): the emulator must send exactly the
//! fixture's reply bytes, and every vector's identifier must split into its annotated fields.

use std::collections::BTreeMap;

use bus::CanFrame;
use rand::{Rng, SeedableRng};
use sim::robstride::{codec, Actuator, Fault, Load, ModeState, Model, MotorConfig, Phase};

use testkit::fixtures::Vector;

/// Every vector of one fixture file, by name; a missing file or a repeated name fails.
fn load(name: &str) -> BTreeMap<String, Vector> {
    let path = testkit::fixtures::repo_path("robstride").join(name);
    let mut out = BTreeMap::new();
    for v in testkit::fixtures::read_file(&path).unwrap_or_else(|e| panic!("{e}")) {
        if let Some(old) = out.insert(v.name.clone(), v) {
            panic!("{}: vector name {} used twice", old.at, old.name);
        }
    }
    out
}

fn vectors() -> BTreeMap<String, Vector> {
    let mut all = load("spec_examples.log");
    for (name, v) in load("reply_matrix.log") {
        assert!(!all.contains_key(&name), "{}: {name} in both files", v.at);
        all.insert(name, v);
    }
    all
}

fn frame(all: &BTreeMap<String, Vector>, name: &str) -> CanFrame {
    all.get(name)
        .unwrap_or_else(|| panic!("fixture {name}"))
        .frame
}

fn field_f64(all: &BTreeMap<String, Vector>, name: &str, key: &str) -> f64 {
    all[name].float(key).unwrap_or_else(|e| panic!("{e}"))
}

fn motor(can_id: u8, model: Model) -> Actuator {
    let mut config = MotorConfig::new(can_id, model);
    config.uid = Some([1, 2, 3, 4, 5, 6, 7, 8]);
    Actuator::new(config, None, 1_000_000)
}

fn single(replies: Vec<CanFrame>) -> CanFrame {
    assert_eq!(replies.len(), 1, "expected one reply, got {replies:?}");
    replies[0]
}

#[test]
fn ping_answers_with_type0_and_the_uid() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "ping"))),
        frame(&all, "ping_reply")
    );
}

#[test]
fn enable_reply_matches_the_worked_example() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "enable"))),
        frame(&all, "enable_reply")
    );
    assert_eq!(rs03.snapshot().mode, ModeState::Run);
}

#[test]
fn version_read_replies_type2_with_the_version_and_stops() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.handle_frame(&frame(&all, "enable"));
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "version_read"))),
        frame(&all, "version_reply")
    );
    assert_eq!(rs03.snapshot().mode, ModeState::Reset);
    assert_eq!(all["version_reply"].fields["version"], "0.3.1.41");
}

#[test]
fn stop_replies_with_reset_state() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.handle_frame(&frame(&all, "enable"));
    for name in ["stop", "stop_clear", "set_zero", "save"] {
        let reply = single(rs03.handle_frame(&frame(&all, name)));
        assert_eq!(reply.raw_id(), 0x0200_7FFD, "{name}");
    }
    assert_eq!(rs03.snapshot().mode, ModeState::Reset);
}

#[test]
fn set_can_id_answers_from_the_new_id_and_only_there() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "set_can_id"))),
        frame(&all, "set_can_id_reply")
    );
    assert!(rs03.handle_frame(&frame(&all, "ping")).is_empty());
    let ping_new = CanFrame::extended(0x0000_FD01, &[0; 8]).unwrap();
    assert_eq!(single(rs03.handle_frame(&ping_new)).raw_id(), 0x0000_01FE);
    assert!(rs03.take_persist_request(), "a new ID is persisted");
}

#[test]
fn set_can_id_is_refused_while_enabled() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.handle_frame(&frame(&all, "enable"));
    assert!(rs03.handle_frame(&frame(&all, "set_can_id")).is_empty());
    assert_eq!(rs03.can_id(), 0x7F);
}

#[test]
fn parameter_writes_and_reads_use_the_documented_layout() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    let reply = single(rs03.handle_frame(&frame(&all, "write_run_mode")));
    assert_eq!(reply.raw_id() >> 24, 2);
    assert_eq!(rs03.snapshot().run_mode, 5);
    // The manual's example reads loc_kp = 30; set it first (RS03's default is 60).
    let write_30 = CanFrame::extended(0x1200_FD7F, &[0x1E, 0x70, 0, 0, 0, 0, 0xF0, 0x41]).unwrap();
    rs03.handle_frame(&write_30);
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "read_loc_kp"))),
        frame(&all, "read_loc_kp_reply")
    );
    rs03.handle_frame(&frame(&all, "write_limit_spd"));
    let read = CanFrame::extended(0x1100_FD7F, &[0x17, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    let reply = single(rs03.handle_frame(&read));
    let value = f32::from_le_bytes(reply.data()[4..8].try_into().unwrap());
    assert_eq!(
        f64::from(value),
        field_f64(&all, "write_limit_spd", "value")
    );
    // The u32 timeout parameter and a negative float.
    let timeout = CanFrame::extended(0x1200_FD7F, &[0x28, 0x70, 0, 0, 0x20, 0x4E, 0, 0]).unwrap();
    rs03.handle_frame(&timeout);
    let read = CanFrame::extended(0x1100_FD7F, &[0x28, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(
        single(rs03.handle_frame(&read)),
        frame(&all, "read_can_timeout_reply")
    );
    rs03.handle_frame(&frame(&all, "write_spd_ref"));
    let read = CanFrame::extended(0x1100_FD7F, &[0x0A, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    let reply = single(rs03.handle_frame(&read));
    let value = f32::from_le_bytes(reply.data()[4..8].try_into().unwrap());
    assert_eq!(f64::from(value), field_f64(&all, "write_spd_ref", "value"));
}

#[test]
fn unreadable_parameters_get_the_failure_echo() {
    let all = vectors();
    let mut rs03 = motor(0x15, Model::RS03);
    let read_string = CanFrame::extended(0x1100_FD15, &[0x03, 0x10, 0, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(
        single(rs03.handle_frame(&read_string)),
        frame(&all, "read_failure_reply")
    );
    // A gap in the 0x70xx table fails the same way.
    let gap = CanFrame::extended(0x1100_FD15, &[0x07, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(single(rs03.handle_frame(&gap)).raw_id(), 0x1101_15FD);
}

#[test]
fn read_only_parameters_refuse_writes_with_the_failure_flag() {
    let mut rs03 = motor(0x7F, Model::RS03);
    let write_mech_pos =
        CanFrame::extended(0x1200_FD7F, &[0x19, 0x70, 0, 0, 0, 0, 0x80, 0x3F]).unwrap();
    let reply = single(rs03.handle_frame(&write_mech_pos));
    assert_eq!(reply.raw_id(), 0x1101_7FFD);
    assert_eq!(&reply.data()[..2], &[0x19, 0x70]);
}

#[test]
fn run_mode_cannot_change_while_running() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.handle_frame(&frame(&all, "enable"));
    let reply = single(rs03.handle_frame(&frame(&all, "write_run_mode")));
    assert_eq!(reply.raw_id() >> 24, 2);
    assert_eq!(rs03.snapshot().run_mode, 0);
}

#[test]
fn active_reporting_sends_type24_every_10_ms() {
    let all = vectors();
    let mut rs00 = motor(0x7F, Model::RS00);
    assert!(rs00
        .handle_frame(&frame(&all, "active_report_on"))
        .is_empty());
    let mut reports = Vec::new();
    for ms in 1..=100u32 {
        for out in rs00.tick() {
            reports.push((ms, out));
        }
    }
    assert_eq!(reports.len(), 10);
    assert!(reports.iter().all(|(ms, _)| ms % 10 == 0));
    let (_, first) = reports[0];
    assert_eq!(first.raw_id(), 0x1800_7FFD);
    assert!(rs00
        .handle_frame(&frame(&all, "active_report_off"))
        .is_empty());
    assert!((0..50).all(|_| rs00.tick().is_empty()));
}

#[test]
fn baud_and_protocol_switches_reply_type0() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    for name in ["baud_500k", "protocol_mit"] {
        let reply = single(rs03.handle_frame(&frame(&all, name)));
        assert_eq!(reply, frame(&all, "ping_reply"), "{name}");
    }
    let saved = rs03.persisted();
    assert_eq!(saved.baud_code, 2);
    assert_eq!(saved.protocol, 2);
    // "After power cycle": still listening now, deaf after a restart.
    assert!(rs03.snapshot().listening);
    let restarted = Actuator::new(rs03.config().clone(), Some(&saved), 1_000_000);
    assert!(!restarted.snapshot().listening);
}

#[test]
fn status_frames_carry_fault_bits_and_type21_words() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    let fault_frame = rs03.inject(Fault::OverTemperature).expect("type 21 sent");
    assert_eq!(fault_frame, frame(&all, "fault_frame"));
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "stop"))),
        frame(&all, "status_over_temp")
    );

    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.inject(Fault::StallOverload);
    let second = rs03.inject(Fault::PhaseOverCurrent(Phase::A));
    assert_eq!(second, Some(frame(&all, "fault_frame_stall")));

    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.inject(Fault::EncoderNotCalibrated);
    assert_eq!(
        single(rs03.handle_frame(&frame(&all, "stop"))),
        frame(&all, "status_uncalibrated")
    );
}

#[test]
fn faults_latch_until_stop_and_clear_after_the_cause_is_gone() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    rs03.inject(Fault::UnderVoltage);
    rs03.handle_frame(&frame(&all, "enable"));
    assert_eq!(
        rs03.snapshot().mode,
        ModeState::Reset,
        "enable refused while faulted"
    );
    rs03.handle_frame(&frame(&all, "stop_clear"));
    assert_ne!(rs03.snapshot().fault_word, 0, "cause still present");
    rs03.remove_cause(Fault::UnderVoltage);
    rs03.tick();
    assert_ne!(rs03.snapshot().fault_word, 0, "latched until cleared");
    rs03.handle_frame(&frame(&all, "stop"));
    assert_ne!(rs03.snapshot().fault_word, 0, "a plain stop does not clear");
    rs03.handle_frame(&frame(&all, "stop_clear"));
    assert_eq!(rs03.snapshot().fault_word, 0);
    rs03.handle_frame(&frame(&all, "enable"));
    assert_eq!(rs03.snapshot().mode, ModeState::Run);
}

#[test]
fn op_control_example_decodes_to_kp_20_and_kd_1() {
    let all = vectors();
    let mut config = MotorConfig::new(0x7F, Model::RS03).with_load(Load::Disc {
        mass_kg: 5.0,
        radius_m: 0.2,
    });
    config.start_angle_rad = 0.5;
    let mut rs03 = Actuator::new(config, None, 1_000_000);
    rs03.handle_frame(&frame(&all, "enable"));
    rs03.handle_frame(&frame(&all, "op_control"));
    rs03.tick();
    let snap = rs03.snapshot();
    // τ = kp·(0 − p) + kd·(0 − v) with kp = 20, kd = 1.
    let expected = -field_f64(&all, "op_control", "kp") * snap.angle_rad
        - field_f64(&all, "op_control", "kd") * snap.speed_rad_s;
    assert!(
        (snap.torque_nm - expected).abs() < 0.1,
        "{} vs {expected}",
        snap.torque_nm
    );
    assert!(snap.torque_nm < -9.0);
}

#[test]
fn status_encoding_matches_the_captured_rs03_frame() {
    let all = vectors();
    let ranges = Model::RS03.ranges(Default::default());
    let name = "captured_stop_reply";
    let data = codec::status_payload(
        field_f64(&all, name, "angle_rad") as f32,
        field_f64(&all, name, "speed_rad_s") as f32,
        field_f64(&all, name, "torque_nm") as f32,
        field_f64(&all, name, "temp_c") as f32,
        &ranges,
    );
    let expected = frame(&all, name);
    // The fixture's decoded fields are rounded; allow a few LSB per field.
    for field in 0..3 {
        let ours = i32::from(u16::from_be_bytes([data[2 * field], data[2 * field + 1]]));
        let theirs = i32::from(u16::from_be_bytes([
            expected.data()[2 * field],
            expected.data()[2 * field + 1],
        ]));
        assert!(
            (ours - theirs).abs() <= 4,
            "field {field}: {ours} vs {theirs}"
        );
    }
    assert_eq!(&data[6..8], &expected.data()[6..8]);
}

#[test]
fn other_motors_frames_and_malformed_frames_are_ignored_without_panic() {
    let mut rs03 = motor(0x01, Model::RS03);
    let mut rng = rand::rngs::SmallRng::seed_from_u64(7);
    for _ in 0..20_000 {
        let len = rng.random_range(0..=8);
        let data: Vec<u8> = (0..len).map(|_| rng.random()).collect();
        let frame = if rng.random_bool(0.9) {
            let id = (rng.random::<u32>() & 0x1FFF_FF00) | u32::from(rs03.can_id());
            CanFrame::extended(id, &data).unwrap()
        } else {
            CanFrame::standard(rng.random_range(0..0x800), &data).unwrap()
        };
        for reply in rs03.handle_frame(&frame) {
            // Replies come from this motor (bits 15..8) or are type 0 to 0xFE.
            let id = reply.raw_id();
            assert!(((id >> 8) & 0xFF) == u32::from(rs03.can_id()));
        }
        rs03.tick();
    }
    // Frames for another motor are never answered.
    let mut other = motor(0x02, Model::RS03);
    let ping = CanFrame::extended(0x0000_FD01, &[0; 8]).unwrap();
    assert!(other.handle_frame(&ping).is_empty());
}

/// Every vector, whichever other test replays it: the identifier splits into the fields the
/// annotation lists (type, host, motor, status bits). A vector without a direction, type or
/// motor, or with an unknown direction, fails.
#[test]
fn every_vector_identifier_matches_its_annotation() {
    let all = vectors();
    assert!(all.len() >= 30, "{} vectors", all.len());
    for v in all.values() {
        let int = |key: &str| v.int(key).unwrap_or_else(|e| panic!("{e}"));
        let id = codec::ExtId::parse(v.frame.raw_id());
        assert!(v.frame.is_extended(), "{v}");
        assert_eq!(i64::from(id.comm.bits()), int("type"), "{v}");
        match v.text("dir").unwrap_or_else(|e| panic!("{e}")) {
            "h2m" => {
                assert_eq!(i64::from(id.dst), int("motor"), "{v}");
                // Type 1 carries the feed-forward torque where other requests name the host.
                if v.has("host") {
                    assert_eq!(i64::from(id.low_data2()), int("host"), "{v}");
                }
                if v.has("new_id") {
                    assert_eq!(i64::from(id.high_data2()), int("new_id"), "{v}");
                }
            }
            "m2h" => {
                assert_eq!(i64::from(id.low_data2()), int("motor"), "{v}");
                let dst = if v.has("dst") {
                    int("dst")
                } else {
                    int("host")
                };
                assert_eq!(i64::from(id.dst), dst, "{v}");
                if v.has("state") {
                    let faults = if v.has("faults") { int("faults") } else { 0 };
                    assert_eq!(
                        i64::from(id.high_data2()),
                        int("state") << 6 | faults,
                        "{v}"
                    );
                }
                if v.has("status") {
                    assert_eq!(i64::from(id.high_data2()), int("status"), "{v}");
                }
            }
            other => panic!("{v}: unknown direction {other}"),
        }
    }
}

/// An encoder glitch (a fault with a value) shifts what the firmware reads, on the wire too,
/// by its counts of the 14-bit encoder's 16,384 per turn, sets no fault bit, and clearing it
/// (its counts left out) puts the reading back.
#[test]
fn an_encoder_glitch_shifts_the_reading_by_its_counts_until_cleared() {
    let all = vectors();
    let mut rs03 = motor(0x7F, Model::RS03);
    let before = rs03.snapshot().angle_rad;
    let status_angle = |rs03: &mut Actuator| {
        let status = single(rs03.handle_frame(&frame(&all, "stop")));
        let raw = u16::from_be_bytes([status.data()[0], status.data()[1]]);
        // Type 2 angles span ±4π over 16 bits (RS03, manual table).
        f64::from(raw) / 65535.0 * 8.0 * std::f64::consts::PI - 4.0 * std::f64::consts::PI
    };
    let wire_before = status_angle(&mut rs03);
    let glitch = sim::robstride::build_fault(
        "encoder_glitch",
        &sim::fault_args::FaultArgs::new()
            .with("motor", sim::fault_args::FaultArgValue::Number(127.0))
            .with("counts", sim::fault_args::FaultArgValue::Number(1024.0)),
    )
    .expect("a glitch of 1024 counts on motor 127");
    assert_eq!(glitch.fault, Fault::EncoderGlitch { counts: 1024 });
    assert_eq!(rs03.inject(glitch.fault), None, "no fault word to report");
    let shift = std::f64::consts::TAU * 1024.0 / 16384.0;
    assert!((rs03.snapshot().angle_rad - before - shift).abs() < 1e-12);
    assert!((status_angle(&mut rs03) - wire_before - shift).abs() < 1e-3);
    assert_eq!(rs03.snapshot().fault_word, 0);
    rs03.remove_cause(Fault::EncoderGlitch { counts: 0 });
    assert!((rs03.snapshot().angle_rad - before).abs() < 1e-12);
}
