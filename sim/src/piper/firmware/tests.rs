//! Streaming clients: SDK demos re-send mode + target every few milliseconds. A repeated
//! target must not restart the profile; a changed one must blend from the current velocity.

use bus::CanFrame;

use super::Firmware;
use crate::piper::PiperConfig;

const MOVE_P: u8 = 0x00;
const MOVE_J: u8 = 0x01;
const MOVE_L: u8 = 0x02;
const MOVE_C: u8 = 0x03;
const SPEED_PCT: u8 = 50;
/// SDK demos re-send every 5 ms.
const RESEND_TICKS: u64 = 5;
/// Upper bound on any move here, ticks.
const TIMEOUT_TICKS: u64 = 8000;

/// The SDK demo's safe pose (150, 0, 260 mm, 0°, 85°, 0°) and points around it.
const POSE_A: [i32; 6] = [150_000, 0, 260_000, 0, 85_000, 0];
const POSE_B: [i32; 6] = [150_000, 88_000, 260_000, 0, 85_000, 0];
const POSE_FAR: [i32; 6] = [150_000, 120_000, 260_000, 0, 85_000, 0];
const ARC_MID: [i32; 6] = [250_000, 0, 250_000, 0, 85_000, 0];
const ARC_START: [i32; 6] = [200_000, -50_000, 250_000, 0, 85_000, 0];
const ARC_END: [i32; 6] = [200_000, 50_000, 250_000, 0, 85_000, 0];

fn frame(id: u16, data: [u8; 8]) -> CanFrame {
    CanFrame::standard(id, &data).expect("a valid standard frame")
}

fn pair(id: u16, a: i32, b: i32) -> CanFrame {
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&a.to_be_bytes());
    d[4..].copy_from_slice(&b.to_be_bytes());
    frame(id, d)
}

fn pose_frames(p: [i32; 6]) -> Vec<CanFrame> {
    vec![
        pair(0x152, p[0], p[1]),
        pair(0x153, p[2], p[3]),
        pair(0x154, p[4], p[5]),
    ]
}

fn joint_frames(mdeg: [i32; 6]) -> Vec<CanFrame> {
    vec![
        pair(0x155, mdeg[0], mdeg[1]),
        pair(0x156, mdeg[2], mdeg[3]),
        pair(0x157, mdeg[4], mdeg[5]),
    ]
}

fn arc_frames() -> Vec<CanFrame> {
    let mut out = Vec::new();
    for (p, idx) in [(ARC_START, 1u8), (ARC_MID, 2), (ARC_END, 3)] {
        out.extend(pose_frames(p));
        out.push(frame(0x158, [idx, 0, 0, 0, 0, 0, 0, 0]));
    }
    out
}

/// One command as an SDK client sends it: mode control, then the target frames.
fn command(mode: u8, target: &[CanFrame]) -> Vec<CanFrame> {
    let mut out = vec![frame(0x151, [1, mode, SPEED_PCT, 0, 0, 0, 0, 0])];
    out.extend_from_slice(target);
    out
}

fn send(fw: &mut Firmware, frames: &[CanFrame]) {
    for f in frames {
        fw.handle_frame(f);
    }
}

fn tick(fw: &mut Firmware) {
    fw.tick();
    fw.take_output();
}

/// Run until the arm reports arrival (motion status 0); the ticks it took.
fn run_until_arrived(fw: &mut Firmware, resend: Option<&[CanFrame]>) -> u64 {
    for t in 1..=TIMEOUT_TICKS {
        if let Some(frames) = resend {
            if t % RESEND_TICKS == 0 {
                send(fw, frames);
            }
        }
        tick(fw);
        if fw.motion_status() == 0 {
            return t;
        }
    }
    panic!("no arrival within {TIMEOUT_TICKS} ticks");
}

/// An enabled arm resting at `POSE_A`.
fn arm_at_pose_a() -> Firmware {
    let mut fw = Firmware::new(PiperConfig {
        initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.3, 0.0],
        ..PiperConfig::default()
    })
    .expect("the firmware boots");
    send(&mut fw, &[frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0])]);
    for _ in 0..20 {
        tick(&mut fw);
    }
    send(&mut fw, &command(MOVE_P, &pose_frames(POSE_A)));
    run_until_arrived(&mut fw, None);
    fw
}

/// Ticks to arrival when `cmd` is sent once, and when it is re-sent every 5 ms.
fn single_and_streamed(cmd: &[CanFrame]) -> (u64, u64) {
    let mut once = arm_at_pose_a();
    send(&mut once, cmd);
    let single = run_until_arrived(&mut once, None);
    let mut streamed = arm_at_pose_a();
    send(&mut streamed, cmd);
    let stream = run_until_arrived(&mut streamed, Some(cmd));
    (single, stream)
}

fn assert_streaming_keeps_the_profile(cmd: &[CanFrame], what: &str) {
    let (single, streamed) = single_and_streamed(cmd);
    // Long enough to be a real move, and streaming changes the arrival by a tick or two.
    assert!(
        single > 300,
        "{what}: single-send move took only {single} ticks"
    );
    assert!(
        single.abs_diff(streamed) <= 2,
        "{what}: single {single} ticks, streamed {streamed} ticks"
    );
}

#[test]
fn streamed_move_j_arrives_when_a_single_send_does() {
    let target = [30_000, 40_000, -40_000, 10_000, 20_000, -15_000];
    assert_streaming_keeps_the_profile(&command(MOVE_J, &joint_frames(target)), "MOVE J");
}

#[test]
fn streamed_move_p_arrives_when_a_single_send_does() {
    assert_streaming_keeps_the_profile(&command(MOVE_P, &pose_frames(POSE_B)), "MOVE P");
}

#[test]
fn streamed_move_l_arrives_when_a_single_send_does() {
    assert_streaming_keeps_the_profile(&command(MOVE_L, &pose_frames(POSE_B)), "MOVE L");
}

#[test]
fn streamed_move_c_arrives_when_a_single_send_does() {
    assert_streaming_keeps_the_profile(&command(MOVE_C, &arc_frames()), "MOVE C");
}

fn speed(v: &[f64; 6]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Start `first`, switch to `second` half-way, and return the reference speed just before
/// and just after the switch plus the largest one-tick velocity change around it.
fn switch_mid_move(first: &[CanFrame], second: &[CanFrame]) -> (f64, f64, f64) {
    let mut fw = arm_at_pose_a();
    send(&mut fw, first);
    let total = {
        let mut probe = arm_at_pose_a();
        send(&mut probe, first);
        run_until_arrived(&mut probe, None)
    };
    for _ in 0..total / 2 {
        tick(&mut fw);
    }
    let before = fw.ref_vel;
    send(&mut fw, second);
    let mut last = before;
    let mut max_dv = 0.0f64;
    for _ in 0..20 {
        tick(&mut fw);
        let dv: [f64; 6] = std::array::from_fn(|j| fw.ref_vel[j] - last[j]);
        max_dv = max_dv.max(speed(&dv));
        last = fw.ref_vel;
    }
    (speed(&before), speed(&fw.ref_vel), max_dv)
}

#[test]
fn changed_joint_target_blends_from_the_current_velocity() {
    let first = command(
        MOVE_J,
        &joint_frames([40_000, 40_000, -40_000, 0, 20_000, 0]),
    );
    let second = command(
        MOVE_J,
        &joint_frames([60_000, 45_000, -45_000, 0, 25_000, 0]),
    );
    let (before, after, max_dv) = switch_mid_move(&first, &second);
    assert!(before > 0.2, "not moving at the switch: {before} rad/s");
    // Acceleration-limited: at most a few rad/s² × 1 ms per tick, never a drop to rest.
    assert!(
        max_dv < 0.05,
        "velocity jumped by {max_dv} rad/s in one tick"
    );
    assert!(
        after > 0.8 * before,
        "slowed from {before} to {after} rad/s"
    );
}

#[test]
fn changed_line_target_blends_from_the_current_velocity() {
    let first = command(MOVE_L, &pose_frames(POSE_B));
    let second = command(MOVE_L, &pose_frames(POSE_FAR));
    let (before, after, max_dv) = switch_mid_move(&first, &second);
    assert!(before > 0.05, "not moving at the switch: {before} rad/s");
    assert!(
        max_dv < 0.1 * before,
        "velocity jumped by {max_dv} rad/s in one tick (speed {before} rad/s)"
    );
    assert!(
        after > 0.8 * before,
        "slowed from {before} to {after} rad/s"
    );
}
