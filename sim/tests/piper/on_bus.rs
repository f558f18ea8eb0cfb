//! The Piper emulator on the virtual bus under a paused clock: rates, replies, state changes.

use std::collections::BTreeMap;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::piper::{FirmwareProfile, PiperConfig, PiperHandle};
use testkit::emulators::piper::{collect, last, spawn_emulator};

fn frame(id: u16, data: [u8; 8]) -> CanFrame {
    CanFrame::standard(id, &data).unwrap()
}

fn start(profile: FirmwareProfile) -> (VirtualBus, VirtualNode, PiperHandle) {
    start_with(profile, 1)
}

fn start_with(
    profile: FirmwareProfile,
    ticks_per_wake: u32,
) -> (VirtualBus, VirtualNode, PiperHandle) {
    spawn_emulator(PiperConfig {
        firmware: profile,
        initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.0, 0.0],
        ticks_per_wake,
        ..PiperConfig::default()
    })
}

#[tokio::test(start_paused = true)]
async fn batched_steps_keep_the_feedback_rates() {
    let (_bus, host, emu) = start_with(FirmwareProfile::V1_8_2, 5);
    collect(&host, Duration::from_millis(100)).await;
    let frames = collect(&host, Duration::from_secs(1)).await;
    let count = |id: u32| frames.iter().filter(|f| f.raw_id() == id).count();
    assert!((199..=201).contains(&count(0x2A1)), "{}", count(0x2A1));
    assert!((199..=201).contains(&count(0x256)), "{}", count(0x256));
    assert!((39..=41).contains(&count(0x263)), "{}", count(0x263));
    assert!(
        (emu.snapshot().time_s - 1.1).abs() < 0.011,
        "{}",
        emu.snapshot().time_s
    );
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn feedback_rates_are_200_and_40_hz_while_disabled() {
    let (_bus, host, emu) = start(FirmwareProfile::V1_8_2);
    // Skip the first 100 ms so the counting window holds only steady-state traffic.
    collect(&host, Duration::from_millis(100)).await;
    let frames = collect(&host, Duration::from_secs(1)).await;
    let mut counts: BTreeMap<u32, usize> = BTreeMap::new();
    for f in &frames {
        *counts.entry(f.raw_id()).or_default() += 1;
    }
    for id in (0x2A1..=0x2A8).chain(0x251..=0x256) {
        let n = counts.get(&id).copied().unwrap_or(0);
        assert!((199..=201).contains(&n), "{id:#x}: {n} frames/s");
    }
    for id in 0x261..=0x266 {
        let n = counts.get(&id).copied().unwrap_or(0);
        assert!((39..=41).contains(&n), "{id:#x}: {n} frames/s");
    }
    let total: usize = counts.values().sum();
    assert!((3030..=3050).contains(&total), "{total} frames/s");
    // Power-on state (spec §8.1): standby, normal, joints disabled.
    assert_eq!(last(&frames, 0x2A1).unwrap(), vec![0; 8]);
    assert_eq!(last(&frames, 0x261).unwrap()[5] & 0x40, 0);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn enable_mode_and_move_j_show_in_the_feedback() {
    let (_bus, host, emu) = start(FirmwareProfile::V1_8_2);
    host.send(frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    host.send(frame(0x151, [1, 1, 50, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(60)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap(), vec![1, 0, 1, 0, 0, 0, 0, 0]);
    for id in 0x261..=0x266 {
        assert_eq!(
            last(&frames, id).unwrap()[5] & 0x40,
            0x40,
            "{id:#x} not enabled"
        );
    }
    // J1 to 10°.
    let j1 = 10_000i32.to_be_bytes();
    let j2 = 28_648i32.to_be_bytes();
    host.send(frame(
        0x155,
        [j1[0], j1[1], j1[2], j1[3], j2[0], j2[1], j2[2], j2[3]],
    ))
    .await
    .unwrap();
    let j3 = (-28_648i32).to_be_bytes();
    host.send(frame(0x156, [j3[0], j3[1], j3[2], j3[3], 0, 0, 0, 0]))
        .await
        .unwrap();
    host.send(frame(0x157, [0; 8])).await.unwrap();
    let frames = collect(&host, Duration::from_millis(50)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[4], 1, "moving");
    let frames = collect(&host, Duration::from_secs(2)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!(status[4], 0, "arrived");
    let fb = last(&frames, 0x2A5).unwrap();
    let j1_mdeg = i32::from_be_bytes([fb[0], fb[1], fb[2], fb[3]]);
    assert!((j1_mdeg - 10_000).abs() <= 100, "J1 at {j1_mdeg} m°");
    let truth = emu.snapshot();
    assert!((truth.joint_positions_rad[0].to_degrees() - 10.0).abs() < 0.1);
    emu.shutdown().await;
}

/// Everything on the wire (frames and timestamps) during a scripted 1.5 s session.
async fn session_log() -> Vec<(Duration, CanFrame)> {
    let (bus, host, emu) = start(FirmwareProfile::V1_8_8);
    let mut tap = bus.tap();
    host.send(frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    host.send(frame(0x151, [1, 1, 80, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let j1 = 20_000i32.to_be_bytes();
    host.send(frame(0x155, [j1[0], j1[1], j1[2], j1[3], 0, 0x6F, 0xE8, 0]))
        .await
        .unwrap();
    host.send(frame(0x4AF, [1, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    emu.shutdown().await;
    let mut out = Vec::new();
    while let Ok(rf) = tap.try_recv() {
        out.push((rf.timestamp, rf.frame));
    }
    out
}

#[test]
fn same_inputs_give_the_same_bytes_and_times() {
    let run = || {
        tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .start_paused(true)
            .build()
            .unwrap()
            .block_on(session_log())
    };
    let a = run();
    let b = run();
    assert!(a.len() > 4000, "{} frames", a.len());
    assert_eq!(a, b);
}
