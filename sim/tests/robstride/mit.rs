//! The MIT protocol variant (after type 25 with F_CMD 2 and a power cycle): every command of
//! `fixtures/robstride/mit.log` gets its documented reply byte for byte, the three mode
//! sequences move the load, faults show in Response 1 and the fault-status reply (no type 21),
//! and private frames are ignored while MIT is in force. Before this, a motor switched to MIT
//! went silent.

use std::collections::BTreeMap;
use std::collections::BTreeSet;

use bus::CanFrame;
use sim::robstride::{
    Actuator, Fault, Load, ModeState, Model, MotorConfig, PersistedMotor, DEFAULT_HOST_ID,
};
use testkit::fixtures::Vector;

const UID: [u8; 8] = [1, 2, 3, 4, 5, 6, 7, 8];

fn vectors() -> BTreeMap<String, Vector> {
    let path = testkit::fixtures::repo_path("robstride").join("mit.log");
    let mut out = BTreeMap::new();
    for v in testkit::fixtures::read_file(&path).unwrap_or_else(|e| panic!("{e}")) {
        if let Some(old) = out.insert(v.name.clone(), v) {
            panic!("{}: vector name {} used twice", old.at, old.name);
        }
    }
    out
}

fn frame(all: &BTreeMap<String, Vector>, name: &str) -> CanFrame {
    all.get(name)
        .unwrap_or_else(|| panic!("fixture {name}"))
        .frame
}

/// A motor powered on with the MIT protocol saved in its flash.
fn mit_motor(model: Model, load: Load) -> Actuator {
    let mut config = MotorConfig::new(0x7F, model).with_load(load);
    config.uid = Some(UID);
    let saved = PersistedMotor {
        can_id: 0x7F,
        master_id: DEFAULT_HOST_ID,
        zero_offset_rad: 0.0,
        params: BTreeMap::new(),
        baud_code: 1,
        protocol: 2,
    };
    Actuator::new(config, Some(&saved), 1_000_000)
}

fn rs03() -> Actuator {
    mit_motor(Model::RS03, Load::default())
}

fn single(replies: Vec<CanFrame>) -> CanFrame {
    assert_eq!(replies.len(), 1, "expected one reply, got {replies:?}");
    replies[0]
}

fn cmd(f_cmd: u8, marker: u8) -> CanFrame {
    CanFrame::standard(0x07F, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, f_cmd, marker]).unwrap()
}

/// The test's own MIT setpoint packer (manual formula), independent of the emulator's.
fn setpoint(angle: f64, speed: f64, kp: f64, kd: f64, torque: f64) -> CanFrame {
    let u = |x: f64, min: f64, max: f64, bits: u32| {
        ((x.clamp(min, max) - min) * f64::from((1u32 << bits) - 1) / (max - min)) as u16
    };
    let p = 4.0 * std::f64::consts::PI;
    let (a, v, kp, kd, t) = (
        u(angle, -p, p, 16),
        u(speed, -20.0, 20.0, 12),
        u(kp, 0.0, 5000.0, 12),
        u(kd, 0.0, 100.0, 12),
        u(torque, -60.0, 60.0, 12),
    );
    let data = [
        (a >> 8) as u8,
        a as u8,
        (v >> 4) as u8,
        (((v & 0xF) << 4) | (kp >> 8)) as u8,
        kp as u8,
        (kd >> 4) as u8,
        (((kd & 0xF) << 4) | (t >> 8)) as u8,
        t as u8,
    ];
    CanFrame::standard(0x07F, &data).unwrap()
}

fn f32_pair(kind: u16, a: f32, b: f32) -> CanFrame {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&a.to_le_bytes());
    data[4..].copy_from_slice(&b.to_le_bytes());
    CanFrame::standard((kind << 8) | 0x7F, &data).unwrap()
}

fn run(m: &mut Actuator, ms: u32) -> Vec<CanFrame> {
    (0..ms).flat_map(|_| m.tick()).collect()
}

#[test]
fn every_command_vector_gets_its_documented_reply() {
    let all = vectors();
    let mut seen = BTreeSet::new();
    for v in all.values().filter(|v| v.fields["dir"] == "h2m") {
        let mut m = rs03();
        let replies = m.handle_frame(&v.frame);
        let kind = v.fields["reply"].as_str();
        seen.insert(kind.to_owned());
        let reply = single(replies);
        assert!(!reply.is_extended(), "{}", v.name);
        match kind {
            "resp1" => {
                assert_eq!(reply.raw_id(), 0x0FD, "{}", v.name);
                assert_eq!(reply.data()[0], 0x7F, "{}", v.name);
            }
            "resp2" => {
                // From the motor's ID: the new one after set-ID.
                let from = if v.name == "mit_set_can_id" {
                    0x05
                } else {
                    0x7F
                };
                assert_eq!(reply.raw_id(), from, "{}", v.name);
                assert_eq!(reply.data(), frame(&all, "mit_resp2").data(), "{}", v.name);
            }
            "fault" => assert_eq!(reply, frame(&all, "mit_fault_reply").with_fault(0)),
            "param" => assert_eq!(reply, frame(&all, &format!("{}_reply", v.name))),
            other => panic!("{}: unknown reply kind {other}", v.name),
        }
    }
    assert_eq!(seen.len(), 4, "{seen:?}");
}

/// The fault-status vector with another fault word (bytes 1..4).
trait WithFault {
    fn with_fault(self, word: u32) -> CanFrame;
}
impl WithFault for CanFrame {
    fn with_fault(self, word: u32) -> CanFrame {
        let mut data = [0u8; 8];
        data.copy_from_slice(self.data());
        data[1..5].copy_from_slice(&word.to_le_bytes());
        CanFrame::standard(self.raw_id() as u16, &data).unwrap()
    }
}

#[test]
fn response1_matches_the_vectors_running_and_faulted() {
    let all = vectors();
    let mut m = rs03();
    assert_eq!(
        single(m.handle_frame(&frame(&all, "mit_enable"))),
        frame(&all, "mit_resp1_run")
    );
    // A fault: the motor stops, sends nothing on its own (no type 21 in MIT), and shows the
    // fault in Response 1 and in the fault-status reply.
    assert_eq!(m.inject(Fault::OverTemperature), None);
    assert_eq!(m.snapshot().mode, ModeState::Reset);
    assert_eq!(
        single(m.handle_frame(&frame(&all, "mit_stop"))),
        frame(&all, "mit_resp1_fault")
    );
    assert_eq!(
        single(m.handle_frame(&frame(&all, "mit_query_fault"))),
        frame(&all, "mit_fault_reply")
    );
    // Enabling is refused while the fault is latched; clearing needs the cause gone.
    let reply = single(m.handle_frame(&frame(&all, "mit_enable")));
    assert_eq!(reply.data()[6] >> 6, 0);
    m.remove_cause(Fault::OverTemperature);
    single(m.handle_frame(&frame(&all, "mit_clear_fault")));
    assert_eq!(m.snapshot().fault_word, 0);
    let reply = single(m.handle_frame(&frame(&all, "mit_enable")));
    assert_eq!(reply.data()[6] >> 6, 2, "running after clear + enable");
}

#[test]
fn mit_setpoint_holds_the_commanded_angle() {
    let mut m = mit_motor(Model::RS03, Load::default());
    single(m.handle_frame(&cmd(0xFF, 0xFC)));
    single(m.handle_frame(&setpoint(1.0, 0.0, 100.0, 2.0, 0.0)));
    run(&mut m, 1500);
    let snap = m.snapshot();
    assert_eq!(snap.run_mode, 0);
    assert!((snap.angle_rad - 1.0).abs() < 0.02, "{snap:?}");
    // The same law from Response 1: angle ≈ 1 rad within one 16-bit step.
    let reply = single(m.handle_frame(&setpoint(1.0, 0.0, 100.0, 2.0, 0.0)));
    let raw = u16::from_be_bytes([reply.data()[1], reply.data()[2]]);
    let p = 4.0 * std::f64::consts::PI;
    let angle = f64::from(raw) * 2.0 * p / 65535.0 - p;
    assert!((angle - 1.0).abs() < 0.02, "{angle}");
    single(m.handle_frame(&cmd(0xFF, 0xFD)));
    assert_eq!(m.snapshot().mode, ModeState::Reset);
}

#[test]
fn position_mode_follows_command_10_at_the_given_speed() {
    let load = Load::Pendulum {
        mass_kg: 0.5,
        length_m: 0.2,
    };
    let mut m = mit_motor(Model::RS03, load);
    // Sequence of §12: set mode 1, enable, command 10.
    single(m.handle_frame(&cmd(0x01, 0xFC)));
    assert_eq!(m.snapshot().run_mode, 5, "position mode is CSP");
    single(m.handle_frame(&cmd(0xFF, 0xFC)));
    single(m.handle_frame(&f32_pair(1, 1.0, 2.0)));
    run(&mut m, 250);
    let mid = m.snapshot();
    assert!(mid.speed_rad_s > 1.5 && mid.speed_rad_s < 2.1, "{mid:?}");
    run(&mut m, 1500);
    let end = m.snapshot();
    assert!((end.angle_rad - 1.0).abs() < 0.02, "{end:?}");
    // Zeroing is refused in position mode.
    single(m.handle_frame(&cmd(0xFF, 0xFE)));
    assert!((m.snapshot().angle_rad - 1.0).abs() < 0.02);
    // A mode change while running is ignored (still answered).
    single(m.handle_frame(&cmd(0x02, 0xFC)));
    assert_eq!(m.snapshot().run_mode, 5);
}

#[test]
fn velocity_mode_follows_command_11() {
    let mut m = rs03();
    single(m.handle_frame(&cmd(0x02, 0xFC)));
    single(m.handle_frame(&cmd(0xFF, 0xFC)));
    single(m.handle_frame(&f32_pair(2, 3.0, 10.0)));
    run(&mut m, 1000);
    let snap = m.snapshot();
    assert_eq!(snap.run_mode, 2);
    assert!((snap.speed_rad_s - 3.0).abs() < 0.05, "{snap:?}");
    assert!(snap.iq_a.abs() <= 10.0 + 1e-9);
    // Stop and zero: the angle reads 0 afterwards.
    single(m.handle_frame(&cmd(0xFF, 0xFD)));
    run(&mut m, 500);
    single(m.handle_frame(&cmd(0xFF, 0xFE)));
    assert!(m.snapshot().angle_rad.abs() < 1e-9);
}

#[test]
fn parameters_save_ids_and_the_switch_back() {
    let all = vectors();
    let mut m = rs03();
    // Write then read through commands 15/14 (the value stored is clamped: RS03 V = 20).
    let write = f32_pair(4, 0.0, 0.0);
    let mut data = [0u8; 8];
    data[..2].copy_from_slice(&0x7017u16.to_le_bytes());
    data[4..].copy_from_slice(&99.0f32.to_le_bytes());
    let write = CanFrame::standard(write.raw_id() as u16, &data).unwrap();
    let reply = single(m.handle_frame(&write));
    assert_eq!(reply.data()[4..], 20.0f32.to_le_bytes());
    // Read-only and unknown indices: no reply.
    data[..2].copy_from_slice(&0x7019u16.to_le_bytes());
    let write_ro = CanFrame::standard(0x47F, &data).unwrap();
    assert!(m.handle_frame(&write_ro).is_empty());
    let read_gap = CanFrame::standard(0x37F, &[0x07, 0x70, 0, 0, 0, 0, 0, 0]).unwrap();
    assert!(m.handle_frame(&read_gap).is_empty());
    // The host tables answer in MIT too (mechPos 0x3016).
    let read_mech = CanFrame::standard(0x37F, &[0x16, 0x30, 0, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(single(m.handle_frame(&read_mech)).raw_id(), 0x37F);
    // Save keeps the written value across a power cycle.
    single(m.handle_frame(&frame(&all, "mit_save")));
    assert_eq!(m.persisted().params[&0x7017], 20.0);
    // Set-ID is refused while running (no reply), accepted while stopped.
    single(m.handle_frame(&frame(&all, "mit_enable")));
    assert!(m.handle_frame(&frame(&all, "mit_set_can_id")).is_empty());
    single(m.handle_frame(&frame(&all, "mit_stop")));
    assert_eq!(
        single(m.handle_frame(&frame(&all, "mit_set_can_id"))).raw_id(),
        0x005
    );
    assert_eq!(m.can_id(), 5);
    // The old ID is no longer answered.
    assert!(m.handle_frame(&frame(&all, "mit_enable")).is_empty());
    // Command 8: private after the next power-on.
    let back = CanFrame::standard(0x005, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0, 0xFD]).unwrap();
    assert_eq!(single(m.handle_frame(&back)).raw_id(), 0x005);
    assert_eq!(m.snapshot().protocol, 2, "still MIT until power-off");
    let saved = m.persisted();
    assert_eq!((saved.protocol, saved.can_id), (0, 5));
    let mut private = Actuator::new(m.config().clone(), Some(&saved), 1_000_000);
    let ping = CanFrame::extended(0x0000_FD05, &[0; 8]).unwrap();
    assert_eq!(single(private.handle_frame(&ping)).raw_id(), 0x0000_05FE);
    assert_eq!(private.snapshot().protocol, 0);
}

#[test]
fn private_frames_are_ignored_and_bad_frames_never_panic() {
    let mut m = rs03();
    let private_enable = CanFrame::extended(0x0300_FD7F, &[0; 8]).unwrap();
    assert!(m.handle_frame(&private_enable).is_empty());
    assert_eq!(m.snapshot().mode, ModeState::Reset);
    // Another motor's ID, short frames, unknown kinds, unknown markers, NaN setpoints.
    for (id, data) in [
        (
            0x07Eu16,
            vec![0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC],
        ),
        (0x07F, vec![0xFF, 0xFF, 0xFF]),
        (0x77F, vec![0; 8]),
        (0x07F, vec![0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x07, 0x55]),
    ] {
        let f = CanFrame::standard(id, &data).unwrap();
        assert!(m.handle_frame(&f).is_empty(), "{f}");
    }
    let nan = f32_pair(1, f32::NAN, f32::INFINITY);
    single(m.handle_frame(&nan));
    assert!(m.snapshot().angle_rad.is_finite());
}

#[test]
fn active_reports_are_response1_frames() {
    let all = vectors();
    let mut m = rs03();
    single(m.handle_frame(&frame(&all, "mit_report_on")));
    let frames = run(&mut m, 100);
    assert_eq!(frames.len(), 10, "every 10 ms");
    assert!(frames
        .iter()
        .all(|f| !f.is_extended() && f.raw_id() == 0x0FD && f.data()[0] == 0x7F));
    single(m.handle_frame(&cmd(0x00, 0xF9)));
    assert!(run(&mut m, 100).is_empty());
}
