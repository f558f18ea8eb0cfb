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
#[ignore]
fn debug_trace() {
    let start = [0.0, 0.5, -0.5, 0.0, 0.0, 0.0];
    let mut fw = boot(FirmwareProfile::V1_8_2, start);
    enable_move_j(&mut fw, 50);
    run(&mut fw, 50);
    let mdeg = [90000, 28648, -28648, 0, 0, 0];
    for f in joints_frames(mdeg) {
        fw.handle_frame(&f);
    }
    for i in 0..2000 {
        fw.tick();
        fw.take_output();
        if i % 50 == 0 {
            let s = fw.snapshot();
            eprintln!(
                "{:.3} q={:?} v={:?} tau={:?} ms={}",
                s.time_s,
                s.reported_joints_rad
                    .map(|x| (x.to_degrees() * 100.0).round() / 100.0),
                s.joint_velocities_rad_s
                    .map(|x| (x * 100.0).round() / 100.0),
                s.joint_torques_nm.map(|x| (x * 100.0).round() / 100.0),
                s.status.motion_status
            );
        }
    }
}
