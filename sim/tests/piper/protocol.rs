//! Protocol behaviour on the virtual bus under a paused clock: host frames from a test node,
//! the emulator's replies checked byte for byte (exchanges in `fixtures/piper/emu_*.log`),
//! and state changes visible in the periodic feedback.

use std::time::Duration;

use super::vectors::{self, PiperVector};
use bus::virtual_bus::{VirtualBus, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::piper::{FirmwareProfile, PiperConfig, PiperHandle};
use testkit::emulators::piper::{collect, last, spawn_emulator};

fn is_periodic(id: u32) -> bool {
    matches!(id, 0x2A1..=0x2A8 | 0x2B1..=0x2B8 | 0x2C1..=0x2C8 | 0x251..=0x256 | 0x261..=0x266 | 0x481..=0x486)
}

fn start(config: PiperConfig) -> (VirtualBus, VirtualNode, PiperHandle) {
    spawn_emulator(config)
}

fn is_host_frame(v: &vectors::Vector) -> bool {
    matches!(v.id16(), 0x121 | 0x150..=0x15F | 0x191 | 0x422 | 0x470..=0x472 | 0x474 | 0x475 | 0x477 | 0x479 | 0x47A | 0x47D | 0x487)
        || (v.id16() == 0x4AF && v.name == "firmware_query")
        || (matches!(v.id16(), 0x181..=0x187) && v.text("mode").is_ok_and(|m| m != "a"))
}

#[tokio::test(start_paused = true)]
async fn exchanges_reply_byte_for_byte() {
    let all = vectors::load();
    let mut blocks: Vec<(String, Vec<CanFrame>, Vec<CanFrame>)> = Vec::new();
    let mut last_line = (String::new(), 0usize);
    for v in &all {
        let Some(block) = &v.block else { continue };
        // Two comments on one frame yield two vectors for the same line: keep one.
        if (v.at.file.clone(), v.frame_line) == last_line {
            continue;
        }
        if blocks.last().is_none_or(|b| &b.0 != block) {
            blocks.push((block.clone(), Vec::new(), Vec::new()));
        }
        let block = blocks.last_mut().unwrap();
        if is_host_frame(v) {
            block.1.push(v.frame);
        } else {
            block.2.push(v.frame);
        }
        last_line = (v.at.file.clone(), v.frame_line);
    }
    assert!(blocks.len() >= 10, "{} exchange blocks", blocks.len());
    for (name, requests, expected) in blocks {
        let (_bus, host, emu) = start(PiperConfig::default());
        for f in &requests {
            host.send(*f).await.unwrap();
            tokio::time::sleep(Duration::from_millis(2)).await;
        }
        let got: Vec<CanFrame> = collect(&host, Duration::from_millis(30))
            .await
            .into_iter()
            .filter(|f| !is_periodic(f.raw_id()))
            .collect();
        assert_eq!(got, expected, "exchange {name}");
        emu.shutdown().await;
    }
}

fn f8(id: u16, data: [u8; 8]) -> CanFrame {
    CanFrame::standard(id, &data).unwrap()
}

fn pair(id: u16, a: i32, b: i32) -> CanFrame {
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&a.to_be_bytes());
    d[4..].copy_from_slice(&b.to_be_bytes());
    f8(id, d)
}

/// Send in order, waiting while the host's transmit queue is full (10 frames by default).
async fn send_all(host: &VirtualNode, frames: &[CanFrame]) {
    for f in frames {
        loop {
            match host.send(*f).await {
                Ok(()) => break,
                Err(bus::BusError::TxQueueFull { .. }) => {
                    tokio::time::sleep(Duration::from_micros(200)).await
                }
                Err(e) => panic!("send failed: {e}"),
            }
        }
    }
}

async fn joints(host: &VirtualNode, mdeg: [i32; 6]) {
    send_all(
        host,
        &[
            pair(0x155, mdeg[0], mdeg[1]),
            pair(0x156, mdeg[2], mdeg[3]),
            pair(0x157, mdeg[4], mdeg[5]),
        ],
    )
    .await;
}

fn i32_at(d: &[u8], at: usize) -> i32 {
    i32::from_be_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]])
}

fn config(profile: FirmwareProfile) -> PiperConfig {
    PiperConfig {
        firmware: profile,
        initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.0, 0.0],
        ..PiperConfig::default()
    }
}

async fn enable_in(host: &VirtualNode, move_mode: u8, speed: u8) {
    send_all(
        host,
        &[
            f8(0x471, [7, 2, 0, 0, 0, 0, 0, 0]),
            f8(0x151, [1, move_mode, speed, 0, 0, 0, 0, 0]),
        ],
    )
    .await;
}

#[tokio::test(start_paused = true)]
async fn target_past_a_limit_is_refused_with_status_0x04() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    enable_in(&host, 0x01, 100).await;
    collect(&host, Duration::from_millis(20)).await;
    // J1 to 160° (limit 150°), J5 to 95° (limit 89°).
    joints(&host, [160_000, 28_648, -28_648, 0, 95_000, 0]).await;
    let frames = collect(&host, Duration::from_millis(500)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!(status[1], 0x04, "arm_status");
    assert_eq!(status[6], 0b1_0001, "limit bits");
    assert_eq!(status[4], 0, "not moving");
    assert!(
        emu.snapshot().joint_positions_rad[0].abs() < 0.01,
        "J1 moved"
    );
    // A valid target clears the status and moves.
    joints(&host, [10_000, 28_648, -28_648, 0, 0, 0]).await;
    let frames = collect(&host, Duration::from_millis(50)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!((status[1], status[6], status[4]), (0, 0, 1));
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn limit_from_0x474_binds_motion() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    // J1 max 5.0°; then a 10° target is refused.
    let mut d = [1u8, 0, 50, 0, 0, 0x7F, 0xFF, 0];
    d[3..5].copy_from_slice(&(-50i16).to_be_bytes());
    host.send(f8(0x474, d)).await.unwrap();
    enable_in(&host, 0x01, 100).await;
    collect(&host, Duration::from_millis(20)).await;
    joints(&host, [10_000, 28_648, -28_648, 0, 0, 0]).await;
    let frames = collect(&host, Duration::from_millis(100)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x04);
    joints(&host, [4_000, 28_648, -28_648, 0, 0, 0]).await;
    collect(&host, Duration::from_millis(1500)).await;
    let q = emu.snapshot().reported_joints_rad[0].to_degrees();
    assert!((q - 4.0).abs() < 0.1, "{q}");
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn quick_stop_damps_and_reset_returns_to_standby() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    enable_in(&host, 0x01, 50).await;
    joints(&host, [30_000, 28_648, -28_648, 0, 0, 0]).await;
    collect(&host, Duration::from_millis(200)).await;
    host.send(f8(0x150, [1, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(100)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!(status[1], 0x01, "e-stop status");
    // Commands are ignored while stopped.
    joints(&host, [0, 28_648, -28_648, 0, 0, 0]).await;
    collect(&host, Duration::from_millis(100)).await;
    assert_eq!(emu.snapshot().status.motion_status, 0);
    host.send(f8(0x150, [2, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(100)).await;
    assert_eq!(
        last(&frames, 0x2A1).unwrap(),
        vec![0; 8],
        "standby after reset"
    );
    for id in 0x261..=0x266 {
        assert_eq!(
            last(&frames, id).unwrap()[5] & 0x40,
            0,
            "{id:#x} still enabled"
        );
    }
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn each_profile_reports_its_mit_code_and_runs_the_mit_law() {
    use sim::piper::codec::mit::{pack, MitCommand, MitRaw};
    for profile in FirmwareProfile::ALL {
        let (_bus, host, emu) = start(config(profile));
        let code = profile.mit_mode_code();
        send_all(
            &host,
            &[
                f8(0x471, [7, 2, 0, 0, 0, 0, 0, 0]),
                f8(0x151, [1, code, 0, 0xAD, 0, 0, 0, 0]),
            ],
        )
        .await;
        let frames = collect(&host, Duration::from_millis(20)).await;
        assert_eq!(last(&frames, 0x2A1).unwrap()[2], code, "{profile}");
        // J6 (no gravity load) to 0.5 rad with kp 5 and the vendor's kd 0.8 (kd 0.2 leaves
        // it ringing for seconds against its 0.025 N·m kinetic friction: ζ ≈ 0.14).
        let cmd = MitCommand {
            p_des_rad: 0.5,
            v_des_rad_s: 0.0,
            kp: 5.0,
            kd: 0.8,
            t_ff_nm: 0.0,
        };
        let packing = profile.mit_packing();
        let data = pack(MitRaw::from_command(&cmd, packing), packing);
        for _ in 0..200 {
            host.send(CanFrame::standard(0x15F, &data).unwrap())
                .await
                .unwrap();
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        let q6 = emu.snapshot().reported_joints_rad[5];
        // Before S-V1.7-3 the firmware negates p_des on J6 (spec §10).
        let expected = if profile.mit_sign_flipped(5) {
            -0.5
        } else {
            0.5
        };
        assert!((q6 - expected).abs() < 0.02, "{profile}: J6 at {q6}");
        emu.shutdown().await;
    }
}

#[tokio::test(start_paused = true)]
async fn end_pose_feedback_follows_the_profile_dh() {
    for (profile, x_um, z_um) in [
        (FirmwareProfile::V1_8_2, 56_128, 213_266),
        (FirmwareProfile::V1_5_8, 54_953, 203_387),
    ] {
        let (_bus, host, emu) = start(PiperConfig {
            firmware: profile,
            ..PiperConfig::default()
        });
        // Hold the power-on pose so the arm does not sag.
        host.send(f8(0x471, [7, 2, 0, 0, 0, 0, 0, 0]))
            .await
            .unwrap();
        collect(&host, Duration::from_millis(200)).await;
        let frames = collect(&host, Duration::from_millis(5)).await;
        let xy = last(&frames, 0x2A2).unwrap();
        let zrx = last(&frames, 0x2A3).unwrap();
        let ryrz = last(&frames, 0x2A4).unwrap();
        assert!(
            (i32_at(&xy, 0) - x_um).abs() <= 200,
            "{profile}: x {}",
            i32_at(&xy, 0)
        );
        assert!(
            (i32_at(&zrx, 0) - z_um).abs() <= 200,
            "{profile}: z {}",
            i32_at(&zrx, 0)
        );
        assert!(
            (i32_at(&ryrz, 0) - 85_000).abs() <= 200,
            "{profile}: ry {}",
            i32_at(&ryrz, 0)
        );
        // And exactly the profile's DH FK of the joint angles in the same group.
        let j: Vec<i32> = [
            (0x2A5, 0),
            (0x2A5, 4),
            (0x2A6, 0),
            (0x2A6, 4),
            (0x2A7, 0),
            (0x2A7, 4),
        ]
        .iter()
        .map(|&(id, at)| i32_at(&last(&frames, id).unwrap(), at))
        .collect();
        let q: [f64; 6] = std::array::from_fn(|i| (f64::from(j[i]) / 1000.0).to_radians());
        let fk = sim::piper::pose::WirePose::from_isometry(&sim::piper::kin::flange(&q, profile))
            .to_wire();
        let fb = [
            i32_at(&xy, 0),
            i32_at(&xy, 4),
            i32_at(&zrx, 0),
            i32_at(&zrx, 4),
            i32_at(&ryrz, 0),
            i32_at(&ryrz, 4),
        ];
        for i in 0..6 {
            // The feedback uses the unrounded angles: allow the FK of a 0.5 m° rounding.
            assert!(
                (fk[i] - fb[i]).abs() <= 10,
                "{profile}: field {i}: fk {fk:?} fb {fb:?}"
            );
        }
        emu.shutdown().await;
    }
}

#[tokio::test(start_paused = true)]
async fn move_p_reaches_the_pose_and_unreachable_gives_0x02() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    enable_in(&host, 0x00, 100).await;
    collect(&host, Duration::from_millis(20)).await;
    // A pose 3 m away: no IK solution.
    send_all(
        &host,
        &[
            pair(0x152, 3_000_000, 0),
            pair(0x153, 200_000, 0),
            pair(0x154, 85_000, 0),
        ],
    )
    .await;
    let frames = collect(&host, Duration::from_millis(50)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x02, "no solution");
    // The SDK demo's safe pose (150, 0, 260 mm, 0, 85°, 0) is reachable.
    let target = [150_000, 0, 260_000, 0, 85_000, 0];
    send_all(
        &host,
        &[
            pair(0x152, target[0], target[1]),
            pair(0x153, target[2], target[3]),
            pair(0x154, target[4], target[5]),
        ],
    )
    .await;
    let frames = collect(&host, Duration::from_secs(4)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!((status[1], status[4]), (0, 0), "status {status:?}");
    let xy = last(&frames, 0x2A2).unwrap();
    let zrx = last(&frames, 0x2A3).unwrap();
    assert!(
        (i32_at(&xy, 0) - target[0]).abs() < 1000,
        "x {}",
        i32_at(&xy, 0)
    );
    assert!(
        (i32_at(&zrx, 0) - target[2]).abs() < 1000,
        "z {}",
        i32_at(&zrx, 0)
    );
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn move_l_keeps_the_flange_on_the_line() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    enable_in(&host, 0x00, 100).await;
    let a = [150_000, 0, 260_000, 0, 85_000, 0];
    send_all(
        &host,
        &[
            pair(0x152, a[0], a[1]),
            pair(0x153, a[2], a[3]),
            pair(0x154, a[4], a[5]),
        ],
    )
    .await;
    collect(&host, Duration::from_secs(4)).await;
    host.send(f8(0x151, [1, 0x02, 30, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let b = [150_000, 80_000, 260_000, 0, 85_000, 0];
    send_all(
        &host,
        &[
            pair(0x152, b[0], b[1]),
            pair(0x153, b[2], b[3]),
            pair(0x154, b[4], b[5]),
        ],
    )
    .await;
    let frames = collect(&host, Duration::from_secs(3)).await;
    let mut max_dev_um = 0;
    for f in frames.iter().filter(|f| f.raw_id() == 0x2A2) {
        max_dev_um = max_dev_um.max((i32_at(f.data(), 0) - 150_000).abs());
    }
    let xy = last(&frames, 0x2A2).unwrap();
    assert!(
        (i32_at(&xy, 4) - 80_000).abs() < 1000,
        "y {}",
        i32_at(&xy, 4)
    );
    assert!(max_dev_um < 2000, "left the line by {max_dev_um} µm");
    assert_eq!(last(&frames, 0x2A1).unwrap()[2], 0x02, "mode_feed MOVE L");
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn move_c_passes_the_middle_point() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    enable_in(&host, 0x00, 100).await;
    let a = [200_000, -50_000, 250_000, 0, 85_000, 0];
    send_all(
        &host,
        &[
            pair(0x152, a[0], a[1]),
            pair(0x153, a[2], a[3]),
            pair(0x154, a[4], a[5]),
        ],
    )
    .await;
    collect(&host, Duration::from_secs(4)).await;
    let m = [250_000, 0, 250_000, 0, 85_000, 0];
    let e = [200_000, 50_000, 250_000, 0, 85_000, 0];
    for (p, idx) in [(a, 1u8), (m, 2), (e, 3)] {
        send_all(
            &host,
            &[
                pair(0x152, p[0], p[1]),
                pair(0x153, p[2], p[3]),
                pair(0x154, p[4], p[5]),
                f8(0x158, [idx, 0, 0, 0, 0, 0, 0, 0]),
            ],
        )
        .await;
    }
    host.send(f8(0x151, [1, 0x03, 50, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_secs(4)).await;
    let closest_to_mid = frames
        .iter()
        .filter(|f| f.raw_id() == 0x2A2)
        .map(|f| {
            (((i32_at(f.data(), 0) - m[0]) as f64).powi(2)
                + ((i32_at(f.data(), 4) - m[1]) as f64).powi(2))
            .sqrt()
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest_to_mid < 2000.0,
        "closest to the middle point: {closest_to_mid} µm"
    );
    let xy = last(&frames, 0x2A2).unwrap();
    assert!(
        (i32_at(&xy, 4) - e[1]).abs() < 1000,
        "ends at y {}",
        i32_at(&xy, 4)
    );
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn gripper_moves_zeroes_and_reports_homed() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&30_000i32.to_be_bytes());
    d[4..6].copy_from_slice(&1000u16.to_be_bytes());
    d[6] = 0x01;
    host.send(f8(0x159, d)).await.unwrap();
    let frames = collect(&host, Duration::from_millis(800)).await;
    let g = last(&frames, 0x2A8).unwrap();
    assert!(
        (i32_at(&g, 0) - 30_000).abs() < 500,
        "stroke {}",
        i32_at(&g, 0)
    );
    assert_eq!(g[6], 0x40, "enabled, never zeroed");
    // Disable + set zero: the current opening becomes 0 and bit 7 (homed) sets.
    host.send(f8(0x159, [0, 0, 0, 0, 0, 0, 0x00, 0xAE]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(20)).await;
    let g = last(&frames, 0x2A8).unwrap();
    assert!(
        i32_at(&g, 0).abs() < 500,
        "stroke after zeroing {}",
        i32_at(&g, 0)
    );
    assert_eq!(g[6], 0x80);
    assert!(emu.snapshot().flash.gripper_homed);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn leader_arm_emits_commands_instead_of_feedback() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    host.send(f8(0x470, [0xFA, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(50)).await;
    assert!(
        last(&frames, 0x2A1).is_some(),
        "the role applies only after standby"
    );
    host.send(f8(0x151, [0, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    collect(&host, Duration::from_millis(20)).await;
    let frames = collect(&host, Duration::from_millis(100)).await;
    assert!(
        last(&frames, 0x2A1).is_none() && last(&frames, 0x251).is_none(),
        "feedback must stop"
    );
    assert_eq!(
        last(&frames, 0x151).unwrap(),
        vec![1, 1, 100, 0xAD, 0, 0, 0, 0]
    );
    let j = last(&frames, 0x155).unwrap();
    let truth = emu.snapshot().reported_joints_rad[1].to_degrees() * 1000.0;
    assert!(
        (f64::from(i32_at(&j, 4)) - truth).abs() < 500.0,
        "leader reports J2 {} vs {truth}",
        i32_at(&j, 4)
    );
    let n151 = frames.iter().filter(|f| f.raw_id() == 0x151).count();
    assert!((19..=21).contains(&n151), "{n151} leader frames in 100 ms");
    // 0xFC: back to a follower in standby, feedback resumes.
    host.send(f8(0x470, [0xFC, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(50)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[0], 0x00);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn id_offsets_move_feedback_and_control() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    host.send(f8(0x470, [0, 0x10, 0x20, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    collect(&host, Duration::from_millis(20)).await;
    // Control on 0x17x now; 0x151 on the base id is ignored.
    send_all(
        &host,
        &[
            f8(0x471, [7, 2, 0, 0, 0, 0, 0, 0]),
            f8(0x151, [1, 1, 50, 0, 0, 0, 0, 0]),
        ],
    )
    .await;
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert!(last(&frames, 0x2A1).is_none());
    assert_eq!(
        last(&frames, 0x2B1).unwrap()[0],
        0x00,
        "base-id mode command ignored"
    );
    host.send(f8(0x171, [1, 1, 50, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2B1).unwrap()[..3], [1, 0, 1]);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn periodic_48x_feedback_switches_on_and_off() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    host.send(f8(0x477, [0, 0, 0x01, 0, 3, 0, 0, 0]))
        .await
        .unwrap();
    collect(&host, Duration::from_millis(100)).await;
    let frames = collect(&host, Duration::from_secs(1)).await;
    for id in 0x481..=0x486 {
        let n = frames.iter().filter(|f| f.raw_id() == id).count();
        assert!((39..=41).contains(&n), "{id:#x}: {n}/s");
    }
    host.send(f8(0x477, [0, 0, 0x02, 0, 3, 0, 0, 0]))
        .await
        .unwrap();
    collect(&host, Duration::from_millis(50)).await;
    let frames = collect(&host, Duration::from_millis(200)).await;
    assert!(frames
        .iter()
        .all(|f| !(0x481..=0x486).contains(&f.raw_id())));
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn state_file_keeps_flash_across_restarts() {
    let dir = std::env::temp_dir().join(format!("armhil-piper-state-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("piper.json");
    let _ = std::fs::remove_file(&path);
    let cfg = PiperConfig {
        state_file: Some(path.clone()),
        ..config(FirmwareProfile::V1_8_2)
    };
    {
        let (_bus, host, emu) = start(cfg.clone());
        let mut d = [4u8, 0, 0, 0, 0, 0, 0, 0];
        d[1..3].copy_from_slice(&700i16.to_be_bytes());
        d[3..5].copy_from_slice(&(-600i16).to_be_bytes());
        d[5..7].copy_from_slice(&200u16.to_be_bytes());
        host.send(f8(0x474, d)).await.unwrap();
        host.send(f8(0x47A, [3, 3, 3, 3, 3, 3, 0, 0]))
            .await
            .unwrap();
        collect(&host, Duration::from_millis(20)).await;
        emu.shutdown().await;
    }
    let (_bus, host, emu) = start(cfg);
    send_all(
        &host,
        &[
            f8(0x472, [4, 1, 0, 0, 0, 0, 0, 0]),
            f8(0x477, [2, 0, 0, 0, 3, 0, 0, 0]),
        ],
    )
    .await;
    let frames = collect(&host, Duration::from_millis(20)).await;
    let l = last(&frames, 0x473).unwrap();
    assert_eq!(l, vec![4, 0x02, 0xBC, 0xFD, 0xA8, 0x00, 0xC8, 0]);
    assert_eq!(last(&frames, 0x47B).unwrap(), vec![3, 3, 3, 3, 3, 3, 0, 0]);
    emu.shutdown().await;
    std::fs::remove_dir_all(&dir).unwrap();
}

#[tokio::test(start_paused = true)]
async fn leader_homing_and_upgrade_silence() {
    let (_bus, host, emu) = start(config(FirmwareProfile::V1_8_2));
    send_all(
        &host,
        &[
            f8(0x470, [0xFA, 0, 0, 0, 0, 0, 0, 0]),
            f8(0x151, [0, 0, 0, 0, 0, 0, 0, 0]),
        ],
    )
    .await;
    collect(&host, Duration::from_millis(50)).await;
    // Leader goes home alone: it stops emitting joint targets while it moves.
    host.send(f8(0x191, [1, 1, 1, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    collect(&host, Duration::from_millis(20)).await;
    let frames = collect(&host, Duration::from_millis(100)).await;
    assert!(
        last(&frames, 0x155).is_none(),
        "joint targets while homing alone"
    );
    assert!(last(&frames, 0x151).is_some());
    // It arrives home (then goes compliant again and may drift under its own weight).
    let mut best = f64::INFINITY;
    for _ in 0..300 {
        collect(&host, Duration::from_millis(10)).await;
        let q = emu.snapshot().reported_joints_rad;
        best = best.min(q.iter().fold(0.0f64, |m, x| m.max(x.abs())));
    }
    assert!(best < 0.01, "leader never got home: {best} rad");
    // Back in drag mode it reports its joints again.
    let frames = collect(&host, Duration::from_millis(50)).await;
    assert!(last(&frames, 0x155).is_some());
    // 0x422 mode 1: the bus goes silent until mode 0.
    host.send(CanFrame::standard(0x422, &[1]).unwrap())
        .await
        .unwrap();
    collect(&host, Duration::from_millis(10)).await;
    assert!(collect(&host, Duration::from_millis(100)).await.is_empty());
    host.send(CanFrame::standard(0x422, &[0]).unwrap())
        .await
        .unwrap();
    assert!(!collect(&host, Duration::from_millis(50)).await.is_empty());
    emu.shutdown().await;
}
