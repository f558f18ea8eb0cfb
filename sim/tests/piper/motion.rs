//! Physics-backed behaviour of the Piper firmware core, driven tick by tick (no bus).

use bus::CanFrame;
use sim::piper::{Firmware, FirmwareProfile, PiperConfig};

fn frame(id: u16, data: [u8; 8]) -> CanFrame {
    CanFrame::standard(id, &data).unwrap()
}

fn joints_frames(mdeg: [i32; 6]) -> [CanFrame; 3] {
    let pair = |id: u16, a: i32, b: i32| {
        let mut d = [0u8; 8];
        d[..4].copy_from_slice(&a.to_be_bytes());
        d[4..].copy_from_slice(&b.to_be_bytes());
        frame(id, d)
    };
    [
        pair(0x155, mdeg[0], mdeg[1]),
        pair(0x156, mdeg[2], mdeg[3]),
        pair(0x157, mdeg[4], mdeg[5]),
    ]
}

fn boot(profile: FirmwareProfile, q0: [f64; 6]) -> Firmware {
    Firmware::new(PiperConfig {
        firmware: profile,
        initial_joints_rad: q0,
        ..PiperConfig::default()
    })
    .unwrap()
}

fn run(fw: &mut Firmware, ms: usize) {
    for _ in 0..ms {
        fw.tick();
    }
    fw.take_output();
}

fn enable_move_j(fw: &mut Firmware, speed: u8) {
    fw.handle_frame(&frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0]));
    fw.handle_frame(&frame(0x151, [1, 1, speed, 0, 0, 0, 0, 0]));
}

#[test]
fn move_j_ninety_degrees_takes_the_time_the_limits_imply() {
    let start = [0.0, 0.5, -0.5, 0.0, 0.0, 0.0];
    let mut fw = boot(FirmwareProfile::V1_8_2, start);
    enable_move_j(&mut fw, 50);
    run(&mut fw, 50);
    let target_deg = [
        90.0,
        0.5f64.to_degrees(),
        -0.5f64.to_degrees(),
        0.0,
        0.0,
        0.0,
    ];
    let mdeg = target_deg.map(|d: f64| (d * 1000.0).round() as i32);
    for f in joints_frames(mdeg) {
        fw.handle_frame(&f);
    }
    let t0 = fw.time_s();
    let mut arrived = None;
    for _ in 0..5000 {
        fw.tick();
        fw.take_output();
        if fw.snapshot().status.motion_status == 0 {
            arrived = Some(fw.time_s() - t0);
            break;
        }
    }
    // 90° at 50 % of 3 rad/s with 5 rad/s²: d/v + v/a.
    let (d, v, a) = (std::f64::consts::FRAC_PI_2, 1.5, 5.0);
    let expected = d / v + v / a;
    let t = arrived.expect("never arrived");
    assert!(
        (t - expected).abs() <= 0.05 * expected,
        "took {t} s, expected {expected} s"
    );
    let s = fw.snapshot();
    assert!(
        (s.reported_joints_rad[0] - d).abs() < 0.1f64.to_radians(),
        "{:?}",
        s.reported_joints_rad
    );
    assert_eq!(s.status.arm_status, 0);
}

#[test]
fn every_joint_tracks_a_move_and_settles() {
    let start = [0.0, 0.8, -0.8, 0.0, 0.3, 0.0];
    for j in 0..6 {
        let mut fw = boot(FirmwareProfile::V1_8_2, start);
        enable_move_j(&mut fw, 100);
        run(&mut fw, 20);
        let mut target = start;
        target[j] += if j == 2 { -0.6 } else { 0.6 };
        let mdeg = target.map(|r: f64| (r.to_degrees() * 1000.0).round() as i32);
        for f in joints_frames(mdeg) {
            fw.handle_frame(&f);
        }
        let t0 = fw.time_s();
        let mut t_arr = None;
        for _ in 0..4000 {
            fw.tick();
            fw.take_output();
            if t_arr.is_none() && fw.snapshot().status.motion_status == 0 {
                t_arr = Some(fw.time_s() - t0);
            }
        }
        let expected = 0.6 / 3.0 + 3.0 / 5.0;
        let expected = if 0.6 < 9.0 / 5.0 {
            2.0 * (0.6f64 / 5.0).sqrt()
        } else {
            expected
        };
        let s = fw.snapshot();
        let err = (s.reported_joints_rad[j] - target[j]).abs().to_degrees();
        eprintln!(
            "joint {} arrived after {:?} (trapezoid {expected:.3}) err {err:.4}°",
            j + 1,
            t_arr
        );
        assert!(err < 0.05, "joint {} error {err}°", j + 1);
        let t = t_arr.unwrap();
        assert!(
            (t - expected).abs() < 0.15 * expected,
            "joint {} took {t}",
            j + 1
        );
    }
}

#[test]
fn feedback_current_and_effort_are_the_torque_the_motor_produced() {
    let mut fw = boot(FirmwareProfile::V1_8_2, [0.0, 1.2, -0.6, 0.0, 0.4, 0.0]);
    enable_move_j(&mut fw, 50);
    for _ in 0..500 {
        fw.tick();
    }
    let frames = fw.take_output();
    let snap = fw.snapshot();
    for j in 0..6 {
        let id = 0x251 + j as u32;
        let f = frames.iter().rev().find(|f| f.raw_id() == id).unwrap();
        let d = f.data();
        let current_ma = i16::from_be_bytes([d[2], d[3]]);
        // The SDK's effort: current × 1.18125 (J1–3) or × 0.95844 (J4–6), in mN·m.
        let k = if j < 3 { 1.18125 } else { 0.95844 };
        let effort_nm = f64::from(current_ma) * k / 1000.0;
        assert!(
            (effort_nm - snap.joint_torques_nm[j]).abs() < 0.01,
            "joint {}: {effort_nm} vs {}",
            j + 1,
            snap.joint_torques_nm[j]
        );
        let pos_mrad = i32::from_be_bytes([d[4], d[5], d[6], d[7]]);
        assert!((f64::from(pos_mrad) / 1000.0 - snap.reported_joints_rad[j]).abs() < 0.001);
    }
    // Holding J2 out against gravity takes real torque.
    assert!(
        snap.joint_torques_nm[1].abs() > 1.0,
        "{:?}",
        snap.joint_torques_nm
    );
}

#[test]
fn disabled_arm_falls_and_reports_it() {
    let mut fw = boot(FirmwareProfile::V1_8_2, [0.0, 1.2, -0.6, 0.0, 0.0, 0.0]);
    run(&mut fw, 1000);
    let snap = fw.snapshot();
    assert!(snap.joint_torques_nm.iter().all(|&t| t == 0.0));
    assert!(
        (snap.joint_positions_rad[1] - 1.2).abs() > 0.05,
        "J2 did not move: {:?}",
        snap.joint_positions_rad
    );
}

#[test]
fn target_past_a_limit_never_moves_the_joint() {
    let mut fw = boot(FirmwareProfile::V1_8_2, [0.0, 0.5, -0.5, 0.0, 0.0, 0.0]);
    enable_move_j(&mut fw, 100);
    run(&mut fw, 10);
    for f in joints_frames([0, 28_648, -28_648, 0, 0, 185_000]) {
        fw.handle_frame(&f);
    }
    let mut max_j6 = 0.0f64;
    for _ in 0..2000 {
        fw.tick();
        max_j6 = max_j6.max(fw.snapshot().reported_joints_rad[5].abs());
    }
    let snap = fw.snapshot();
    assert_eq!(snap.status.arm_status, 0x04);
    assert_eq!(snap.status.limit_bits, 0b10_0000);
    assert!(max_j6 < 0.01, "J6 moved to {max_j6} rad");
}

#[test]
fn mit_law_torque_follows_kp_kd_and_firmware_scaling() {
    use sim::piper::codec::mit::{pack, MitCommand, MitRaw};
    for profile in [FirmwareProfile::V1_8_2, FirmwareProfile::V1_8_8] {
        let mut fw = boot(profile, [0.0, 0.5, -0.5, 0.0, 0.0, 0.0]);
        fw.handle_frame(&frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0]));
        fw.handle_frame(&frame(
            0x151,
            [1, profile.mit_mode_code(), 0, 0xAD, 0, 0, 0, 0],
        ));
        // Pure feed-forward on J1 (vertical axis, no gravity): kp = kd = 0, t_ff = 1 N·m.
        let cmd = MitCommand {
            p_des_rad: 0.0,
            v_des_rad_s: 0.0,
            kp: 0.0,
            kd: 0.0,
            t_ff_nm: 1.0,
        };
        let packing = profile.mit_packing();
        let raw = MitRaw::from_command(&cmd, packing);
        fw.handle_frame(&frame(0x15A, pack(raw, packing)));
        fw.tick();
        let executed = fw.snapshot().joint_torques_nm[0];
        let decoded = raw.to_command(packing).t_ff_nm;
        // ≤ S-V1.8-2 executes J1–3 torques ×4 (spec §10).
        let expected = decoded * profile.mit_torque_factor(0);
        // kd = 0 quantises to -0.0012 N·m·s/rad: allow its tiny contribution.
        assert!(
            (executed - expected).abs() < 1e-3,
            "{profile}: {executed} vs {expected}"
        );
    }
}

#[test]
fn random_frames_never_panic_the_firmware() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::SmallRng::seed_from_u64(0x5EED);
    for profile in FirmwareProfile::ALL {
        let mut fw = boot(profile, [0.0, 0.5, -0.5, 0.0, 0.0, 0.0]);
        enable_move_j(&mut fw, 50);
        for _ in 0..3000 {
            // Mostly ids the firmware listens to, some it does not; any length and payload.
            let id: u16 = match rng.random_range(0..4) {
                0 => rng.random_range(0x150..=0x15F),
                1 => rng.random_range(0x470..=0x47F),
                2 => *[0x121u16, 0x191, 0x422, 0x4AF, 0x181, 0x187]
                    .get(rng.random_range(0..6))
                    .unwrap(),
                _ => rng.random_range(0..=0x7FF),
            };
            let len = rng.random_range(0..=8);
            let data: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            fw.handle_frame(&CanFrame::standard(id, &data).unwrap());
            fw.tick();
            fw.take_output();
        }
        let s = fw.snapshot();
        assert!(
            s.joint_positions_rad.iter().all(|q| q.is_finite()),
            "{profile}: {s:?}"
        );
    }
}
