//! The Realman driver against the Realman emulator: over in-memory streams under a paused clock
//! (virtual time, the UDP push carried by a channel) and over real TCP/UDP on 127.0.0.1.

use std::f64::consts::PI;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::Arc;
use std::time::Duration;

use driver::realman::{
    ArmState, ArmStatus, ClientConfig, Connect, ControllerError, Device, GripperMode,
    JointSpeedUnit, MoveOpts, Pose, PushCustom, PushSettings, RealmanClient, RealmanError,
    StateFeed, TrajectoryKind,
};
use sim::realman::model::ArmModel;
use sim::realman::{
    kinematics, ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanFault, RealmanFaultKind,
    RealmanHandle, Transport,
};
use tokio::sync::mpsc;
use tokio::time::{sleep, timeout, Instant};

/// The IP the in-memory client claims (the push aims at it).
const PEER: Ipv4Addr = Ipv4Addr::new(192, 168, 1, 10);
/// The default push port (docs/protocols/realman.md §11).
const PUSH_PORT: u16 = 8089;

fn rad(deg: &[f64]) -> Vec<f64> {
    deg.iter().map(|d| d.to_radians()).collect()
}

fn deg(rad: &[f64]) -> Vec<f64> {
    rad.iter().map(|r| r.to_degrees()).collect()
}

/// Whether joints (rad) are within 0.01° of `target_deg`, judged in the wire's 0.001° units
/// (the unit the controller reports in, so 10 units is the whole allowance).
fn at_deg(joints_rad: &[f64], target_deg: &[f64]) -> bool {
    assert_eq!(joints_rad.len(), target_deg.len());
    joints_rad.iter().zip(target_deg).all(|(q, t)| {
        let got = (q.to_degrees() * 1000.0).round() as i64;
        let want = (t * 1000.0).round() as i64;
        (got - want).abs() <= 10
    })
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Angle difference wrapped to (−π, π].
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI {
        d - 2.0 * PI
    } else {
        d
    }
}

/// Position error (m) and largest Euler error (rad) between two poses.
fn pose_error(a: &Pose, b: &Pose) -> (f64, f64) {
    let p = a
        .position_m
        .iter()
        .zip(&b.position_m)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    let e = a
        .euler_rad
        .iter()
        .zip(&b.euler_rad)
        .map(|(x, y)| angle_diff(*x, *y).abs())
        .fold(0.0, f64::max);
    (p, e)
}

fn emulator_config() -> EmulatorConfig {
    EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b()))
}

/// The driver's view of one emulator: a command connection and a state feed.
struct Bench {
    emu: RealmanHandle,
    arm: RealmanClient,
    feed: StateFeed,
}

/// In-memory emulator and driver (call under a paused clock). Datagrams addressed to
/// `PEER:8089` reach the driver's feed, as on a host listening there.
async fn virtual_bench() -> Bench {
    let emu = RealmanEmulator::spawn(emulator_config(), Transport::InMemory)
        .await
        .expect("emulator starts");
    let mut datagrams = emu.take_datagrams().expect("in-memory datagram stream");
    let (tx, rx) = mpsc::channel(1024);
    let host = SocketAddr::new(IpAddr::V4(PEER), PUSH_PORT);
    tokio::spawn(async move {
        while let Some(d) = datagrams.recv().await {
            if d.to == host && tx.send(d.payload.into_bytes()).await.is_err() {
                break;
            }
        }
    });
    let feed = StateFeed::from_channel(rx, JointSpeedUnit::default());
    let arm = virtual_client(&emu).await;
    Bench { emu, arm, feed }
}

async fn virtual_client(emu: &RealmanHandle) -> RealmanClient {
    let stream = emu.connect(IpAddr::V4(PEER)).expect("in-memory connect");
    RealmanClient::from_stream(stream, ClientConfig::default()).await
}

/// Push settings aimed at `ip:port` with the motion status and joint speeds included.
fn push_to(ip: Ipv4Addr, port: u16, period_ms: u32) -> PushSettings {
    PushSettings {
        period_ms,
        enable: true,
        port,
        ip,
        force_coordinate: None,
        custom: PushCustom {
            joint_speed: Some(true),
            arm_current_status: Some(true),
            ..PushCustom::default()
        },
    }
}

/// The next sample that satisfies `pred`, within `within`.
async fn sample_where(
    feed: &StateFeed,
    within: Duration,
    pred: impl Fn(&ArmState) -> bool,
) -> Option<Arc<ArmState>> {
    let mut watch = feed.watch();
    timeout(within, async {
        loop {
            if let Some(s) = watch.borrow_and_update().clone() {
                if pred(&s) {
                    return s;
                }
            }
            if watch.changed().await.is_err() {
                std::future::pending::<()>().await;
            }
        }
    })
    .await
    .ok()
}

/// A sample taken after now (so it reflects the state after what just happened).
async fn fresh_sample(feed: &StateFeed) -> Arc<ArmState> {
    let mut rx = feed.subscribe();
    timeout(Duration::from_secs(2), rx.recv())
        .await
        .expect("a push sample within 2 s")
        .expect("feed open")
}

const A_POSE_DEG: [f64; 6] = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0];

// ---------------------------------------------------------------- virtual time

#[tokio::test(start_paused = true)]
async fn handshake_reports_an_rm65b_at_power_on() {
    let b = virtual_bench().await;
    let h = b.arm.handshake().await.expect("handshake");
    assert_eq!(h.software.product_version, "RM65-B");
    assert_eq!(h.software.dof, 6);
    assert_eq!(h.trajectory.kind, TrajectoryKind::None);
    assert!(max_abs_diff(&h.trajectory.joints_rad, &[0.0; 6]) < 1e-9);
    assert!(h.push.enable);
    assert_eq!(h.push.period_ms, 5);
    assert_eq!(h.push.port, PUSH_PORT);
    let model = ArmModel::rm65b();
    assert_eq!(h.joint_min_rad.len(), model.dof);
    for j in 0..model.dof {
        let (lo, hi) = (model.joint_min_deg[j], model.joint_max_deg[j]);
        assert!((h.joint_min_rad[j].to_degrees() - lo).abs() < 1e-3, "j{j}");
        assert!((h.joint_max_rad[j].to_degrees() - hi).abs() < 1e-3, "j{j}");
        assert!(h.joint_max_speed_rad_s[j] > 0.0);
        assert!(h.joint_max_acc_rad_s2[j] > h.joint_max_speed_rad_s[j]);
    }
    assert_eq!(h.dh.len(), 6);
    // The power-on push reaches the host holding the connection: the boot pose, no errors.
    let s = fresh_sample(&b.feed).await;
    assert!(max_abs_diff(&s.joints_rad, &[0.0; 6]) < 1e-9);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert!((s.pose.position_m[2] - 0.8505).abs() < 1e-6, "{:?}", s.pose);
    assert_eq!(b.feed.decode_errors(), 0);
}

#[tokio::test(start_paused = true)]
async fn blocking_movej_returns_once_the_arm_is_at_the_target() {
    let b = virtual_bench().await;
    let target = rad(&A_POSE_DEG);
    let start = Instant::now();
    b.arm
        .movej(&target, MoveOpts::speed(30), true)
        .await
        .expect("movej arrives");
    let took = start.elapsed();
    // 60° on J6 at 30 % of 225 °/s needs close to a second; far longer means it waited for nothing.
    assert!(
        took > Duration::from_millis(700) && took < Duration::from_secs(5),
        "{took:?}"
    );
    // Arrival means at the target: the controller's reply and the push agree within 0.01°.
    let by_query = b.arm.joint_positions().await.unwrap();
    assert!(at_deg(&by_query, &A_POSE_DEG), "{:?}", deg(&by_query));
    let pushed = fresh_sample(&b.feed).await;
    assert!(
        at_deg(&pushed.joints_rad, &A_POSE_DEG),
        "{:?}",
        deg(&pushed.joints_rad)
    );
    assert_eq!(
        b.arm.current_trajectory().await.unwrap().kind,
        TrajectoryKind::None
    );
    // The reported pose is the forward kinematics of the reported joints.
    let fk = kinematics::forward(&ArmModel::rm65b(), &pushed.joints_rad);
    let (dp, de) = pose_error(
        &pushed.pose,
        &Pose {
            position_m: fk.position_m,
            euler_rad: fk.euler_rad,
        },
    );
    assert!(dp < 2e-5 && de < 2e-3, "{dp} m, {de} rad");
}

#[tokio::test(start_paused = true)]
async fn movel_ends_at_the_pose_forward_kinematics_gives() {
    let b = virtual_bench().await;
    let model = ArmModel::rm65b();
    b.arm
        .movej(
            &rad(&[0.0, 20.0, 60.0, 0.0, 60.0, 0.0]),
            MoveOpts::speed(50),
            true,
        )
        .await
        .unwrap();
    let aim = rad(&[10.0, 25.0, 55.0, 5.0, 55.0, 10.0]);
    let fk = kinematics::forward(&model, &aim);
    let target = Pose {
        position_m: fk.position_m,
        euler_rad: fk.euler_rad,
    };
    let before = b.arm.arm_state().await.unwrap().pose;
    b.arm
        .movel(&target, MoveOpts::speed(40), true)
        .await
        .expect("movel arrives");
    let after = b.arm.arm_state().await.unwrap();
    let (dp, de) = pose_error(&after.pose, &target);
    assert!(dp < 5e-4 && de < 3e-3, "{dp} m, {de} rad: {after:?}");
    let (moved, _) = pose_error(&before, &target);
    assert!(moved > 0.02, "the test must move the tool: {moved} m");
    // And the pose the controller reports is the FK of its joints.
    let fk_now = kinematics::forward(&model, &after.joints_rad);
    let (dp, de) = pose_error(
        &after.pose,
        &Pose {
            position_m: fk_now.position_m,
            euler_rad: fk_now.euler_rad,
        },
    );
    assert!(dp < 2e-5 && de < 2e-3, "{dp} m, {de} rad");
}

#[tokio::test(start_paused = true)]
async fn a_target_beyond_the_joint_limits_is_refused_and_the_arm_stays_still() {
    let b = virtual_bench().await;
    let mut target = vec![0.0; 6];
    target[0] = 179f64.to_radians();
    let err = b
        .arm
        .movej(&target, MoveOpts::speed(20), true)
        .await
        .expect_err("refused");
    assert!(
        matches!(
            err,
            RealmanError::Rejected {
                command: "movej",
                key: "receive_state"
            }
        ),
        "{err:?}"
    );
    sleep(Duration::from_millis(500)).await;
    let state = b.arm.arm_state().await.unwrap();
    assert!(
        max_abs_diff(&state.joints_rad, &[0.0; 6]) < 1e-9,
        "{state:?}"
    );
    assert!(
        state
            .errors
            .contains(&ControllerError::TargetBeyondJointLimit),
        "{:?}",
        state.errors
    );
    let s = fresh_sample(&b.feed).await;
    assert!(max_abs_diff(&s.joints_rad, &[0.0; 6]) < 1e-9);
    // Within the limits the same joint moves.
    target[0] = 170f64.to_radians();
    b.arm
        .movej(&target, MoveOpts::speed(100), true)
        .await
        .unwrap();
    let q = b.arm.joint_positions().await.unwrap();
    assert!(at_deg(&q, &[170.0, 0.0, 0.0, 0.0, 0.0, 0.0]), "{q:?}");
}

#[tokio::test(start_paused = true)]
async fn pause_holds_the_arm_on_its_path_and_continue_finishes_the_move() {
    let b = virtual_bench().await;
    b.arm
        .set_realtime_push(&push_to(PEER, PUSH_PORT, 5))
        .await
        .unwrap();
    let mut arrivals = b.arm.arrivals();
    let target = rad(&[60.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    b.arm
        .movej(&target, MoveOpts::speed(10), false)
        .await
        .unwrap();
    sleep(Duration::from_millis(1000)).await;
    let moving = fresh_sample(&b.feed).await;
    assert_eq!(moving.status, Some(ArmStatus::MoveJ));
    b.arm.pause().await.expect("pause");
    sleep(Duration::from_millis(400)).await;
    let held = fresh_sample(&b.feed).await;
    assert_eq!(held.status, Some(ArmStatus::Pause));
    let j1 = held.joints_rad[0].to_degrees();
    assert!(j1 > 5.0 && j1 < 55.0, "paused mid-way: {j1}°");
    sleep(Duration::from_secs(1)).await;
    let later = fresh_sample(&b.feed).await;
    assert!(
        (later.joints_rad[0].to_degrees() - j1).abs() < 0.01,
        "held: {j1}° then {}°",
        later.joints_rad[0].to_degrees()
    );
    assert!(arrivals.try_recv().is_err(), "no arrival while paused");
    b.arm.resume().await.expect("continue");
    let (_, event) = timeout(Duration::from_secs(10), arrivals.recv())
        .await
        .expect("arrival after continue")
        .unwrap();
    assert!(event.ok && event.device == Device::Arm && !event.more_follow);
    let q = b.arm.joint_positions().await.unwrap();
    assert!(at_deg(&q, &[60.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    // Continue without a pause is refused.
    assert!(matches!(
        b.arm.resume().await,
        Err(RealmanError::Rejected { .. })
    ));
}

/// Queues three joint moves with `trajectory_connect` 1 and starts them with a fourth;
/// returns how long the whole group took and how many arrival events came.
async fn run_queue(b: &Bench, blend_percent: u8) -> (Duration, usize) {
    let waypoints = [
        [20.0, 10.0, 20.0, 0.0, 20.0, 0.0],
        [40.0, 20.0, 40.0, 0.0, 40.0, 0.0],
        [60.0, 30.0, 60.0, 0.0, 60.0, 0.0],
        [80.0, 40.0, 80.0, 0.0, 80.0, 0.0],
    ];
    b.arm
        .movej(&[0.0; 6], MoveOpts::speed(100), true)
        .await
        .unwrap();
    let mut arrivals = b.arm.arrivals();
    let queued = MoveOpts {
        speed_percent: 50,
        blend_percent,
        connect: Connect::Queue,
    };
    for w in &waypoints[..3] {
        b.arm.movej(&rad(w), queued, true).await.unwrap();
    }
    // Queued moves do not run until the group is closed.
    sleep(Duration::from_millis(300)).await;
    let q = b.arm.joint_positions().await.unwrap();
    assert!(
        max_abs_diff(&q, &[0.0; 6]) < 1e-9,
        "queued moves ran: {q:?}"
    );
    let start = Instant::now();
    let last = MoveOpts {
        connect: Connect::Start,
        ..queued
    };
    b.arm
        .movej(&rad(&waypoints[3]), last, true)
        .await
        .expect("the group arrives");
    let took = start.elapsed();
    let q = b.arm.joint_positions().await.unwrap();
    assert!(at_deg(&q, &waypoints[3]), "{:?}", deg(&q));
    let mut events = Vec::new();
    while let Ok((_, e)) = arrivals.try_recv() {
        events.push(e);
    }
    assert!(events.iter().all(|e| e.ok && e.device == Device::Arm));
    assert!(events.last().is_some_and(|e| !e.more_follow), "{events:?}");
    assert!(
        events[..events.len() - 1].iter().all(|e| e.more_follow),
        "{events:?}"
    );
    (took, events.len())
}

#[tokio::test(start_paused = true)]
async fn a_trajectory_connect_queue_runs_as_one_group_and_blending_shortens_it() {
    let b = virtual_bench().await;
    let (sharp, sharp_events) = run_queue(&b, 0).await;
    let (blended, blended_events) = run_queue(&b, 50).await;
    assert_eq!(sharp_events, 4, "one event per segment");
    assert_eq!(blended_events, 4, "one event per part, blended or not");
    assert!(
        blended < sharp,
        "blending must not stop at the via points: {blended:?} vs {sharp:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn blocking_gripper_commands_return_when_the_gripper_stops() {
    let b = virtual_bench().await;
    let g = b.arm.gripper_state().await.unwrap();
    assert!(g.online && g.enabled, "{g:?}");
    assert_eq!(g.position, 1000);
    let start = Instant::now();
    b.arm
        .gripper_position(500, true)
        .await
        .expect("gripper arrives");
    assert!(start.elapsed() > Duration::from_millis(100));
    let g = b.arm.gripper_state().await.unwrap();
    assert_eq!(g.position, 500, "{g:?}");
    assert_eq!(g.mode, GripperMode::StoppedIdle);
    b.arm.gripper_release(1000, true).await.unwrap();
    let g = b.arm.gripper_state().await.unwrap();
    assert_eq!((g.position, g.mode), (1000, GripperMode::OpenIdle));
    b.arm.gripper_pick(500, 200, true).await.unwrap();
    let g = b.arm.gripper_state().await.unwrap();
    assert!(g.position < 1000, "{g:?}");
    // A gripper fault makes gripper commands fail and shows as error 0x2001.
    b.emu
        .inject(RealmanFault::GripperFault { bits: 1 })
        .unwrap();
    let err = b.arm.gripper_position(800, true).await.unwrap_err();
    assert!(matches!(err, RealmanError::Rejected { .. }), "{err:?}");
    let errors = b.arm.arm_state().await.unwrap().errors;
    assert!(
        errors.contains(&ControllerError::GripperFault),
        "{errors:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn blocking_hand_commands_return_when_the_fingers_stop() {
    let b = virtual_bench().await;
    let start = Instant::now();
    b.arm.hand_posture(3, true).await.expect("hand arrives");
    let took = start.elapsed();
    assert!(
        took > Duration::ZERO && took < Duration::from_secs(5),
        "{took:?}"
    );
    b.arm
        .hand_angles([Some(0), Some(0), Some(0), Some(0), Some(500), None], true)
        .await
        .expect("hand angles arrive");
}

/// Datagrams the feed receives in one simulated second, after the settings took effect.
async fn datagrams_per_second(feed: &StateFeed) -> usize {
    sleep(Duration::from_millis(100)).await;
    let mut rx = feed.subscribe();
    sleep(Duration::from_secs(1)).await;
    let mut n = 0;
    while rx.try_recv().is_ok() {
        n += 1;
    }
    n
}

#[tokio::test(start_paused = true)]
async fn the_push_comes_every_cycle_times_5_ms() {
    let b = virtual_bench().await;
    let at_1 = datagrams_per_second(&b.feed).await;
    assert!((199..=201).contains(&at_1), "cycle 1: {at_1} datagrams/s");
    b.arm
        .set_realtime_push(&push_to(PEER, PUSH_PORT, 20))
        .await
        .unwrap();
    assert_eq!(b.arm.realtime_push().await.unwrap().period_ms, 20);
    let at_4 = datagrams_per_second(&b.feed).await;
    assert!((49..=51).contains(&at_4), "cycle 4: {at_4} datagrams/s");
    // Aimed elsewhere, nothing reaches this host.
    b.arm
        .set_realtime_push(&push_to(Ipv4Addr::new(10, 0, 0, 7), PUSH_PORT, 5))
        .await
        .unwrap();
    assert_eq!(datagrams_per_second(&b.feed).await, 0);
    assert_eq!(b.feed.decode_errors(), 0);
}

#[tokio::test(start_paused = true)]
async fn two_clients_at_once_each_get_their_own_replies_and_events() {
    let b = virtual_bench().await;
    let other = virtual_client(&b.emu).await;
    let mut other_events = other.arrivals();
    let target = rad(&A_POSE_DEG);
    let watcher = async {
        // Polls concurrently while the first client's move runs and sees it progress.
        let mut seen = Vec::new();
        for _ in 0..40 {
            let q = other
                .joint_positions()
                .await
                .expect("second client's query");
            let sw = other.software_info().await.expect("interleaved query");
            assert_eq!(sw.dof, 6);
            seen.push(q[5].to_degrees());
            sleep(Duration::from_millis(25)).await;
        }
        seen
    };
    let (moved, seen) = tokio::join!(b.arm.movej(&target, MoveOpts::speed(30), true), watcher);
    moved.expect("first client's move arrives");
    assert!(seen.windows(2).all(|w| w[1] >= w[0] - 1e-3), "{seen:?}");
    assert!(seen.last().unwrap() - seen[0] > 10.0, "{seen:?}");
    assert!(
        other_events.try_recv().is_err(),
        "the second client sees no event for the first one's move"
    );
    // The second client can move the arm too, and only it is told of the arrival.
    let mut first_events = b.arm.arrivals();
    other
        .movej(&[0.0; 6], MoveOpts::speed(50), true)
        .await
        .unwrap();
    assert!(first_events.try_recv().is_err());
    assert_eq!(b.emu.connections(), 2);
}

#[tokio::test(start_paused = true)]
async fn a_dropped_connection_fails_requests_and_a_reconnect_recovers() {
    let b = virtual_bench().await;
    b.arm
        .movej(&rad(&A_POSE_DEG), MoveOpts::speed(10), false)
        .await
        .unwrap();
    let moving = tokio::spawn({
        let arm = b.arm.clone();
        async move { arm.movej(&[0.0; 6], MoveOpts::speed(10), true).await }
    });
    sleep(Duration::from_millis(100)).await;
    b.emu
        .inject(RealmanFault::ConnectionDrop { peer_ip: None })
        .unwrap();
    sleep(Duration::from_millis(10)).await;
    assert!(!b.arm.is_connected());
    let err = b.arm.joint_positions().await.unwrap_err();
    assert!(matches!(err, RealmanError::Disconnected { .. }), "{err:?}");
    let outstanding = moving.await.unwrap();
    assert!(outstanding.is_ok() || matches!(outstanding, Err(RealmanError::Disconnected { .. })));
    b.arm
        .reconnect_with(b.emu.connect(IpAddr::V4(PEER)).unwrap())
        .await;
    assert!(b.arm.is_connected());
    let q = b
        .arm
        .joint_positions()
        .await
        .expect("works after reconnect");
    assert_eq!(q.len(), 6);
    assert_eq!(b.emu.connections(), 1);
}

#[tokio::test(start_paused = true)]
async fn a_delayed_reply_times_out_after_500_ms_and_is_not_mistaken_later() {
    let b = virtual_bench().await;
    b.emu
        .inject(RealmanFault::ReplyDelay { delay_ms: 600 })
        .unwrap();
    let start = Instant::now();
    let err = b.arm.joint_positions().await.unwrap_err();
    assert!(
        matches!(err, RealmanError::Timeout { command: "get_joint_degree", after } if after == Duration::from_millis(500)),
        "{err:?}"
    );
    assert_eq!(start.elapsed(), Duration::from_millis(500));
    b.emu.clear(RealmanFaultKind::ReplyDelay);
    // Move the arm so a stale reply (all zeros) would be visible, then ask again.
    sleep(Duration::from_millis(200)).await;
    b.arm
        .movej(&rad(&A_POSE_DEG), MoveOpts::speed(50), true)
        .await
        .unwrap();
    let q = b
        .arm
        .joint_positions()
        .await
        .expect("answered once cleared");
    assert!(at_deg(&q, &A_POSE_DEG), "{:?}", deg(&q));
}

#[tokio::test(start_paused = true)]
async fn a_joint_error_aborts_the_move_and_shows_in_the_push() {
    let b = virtual_bench().await;
    b.arm
        .movej(&rad(&A_POSE_DEG), MoveOpts::speed(10), false)
        .await
        .unwrap();
    let moving = tokio::spawn({
        let arm = b.arm.clone();
        async move { arm.movej(&[0.0; 6], MoveOpts::speed(10), true).await }
    });
    sleep(Duration::from_millis(300)).await;
    b.emu
        .inject(RealmanFault::JointError {
            joint: 3,
            code: 0x0008,
        })
        .unwrap();
    let result = moving.await.unwrap();
    assert!(
        matches!(
            result,
            Err(RealmanError::MotionFailed {
                device: Device::Arm,
                ..
            })
        ),
        "{result:?}"
    );
    let s = sample_where(&b.feed, Duration::from_secs(1), |s| !s.errors.is_empty())
        .await
        .expect("the error reaches the push");
    assert!(
        s.errors.contains(&ControllerError::JointCommsAbnormal),
        "{:?}",
        s.errors
    );
    assert_eq!(s.joint_errors[2].0 & 0x0008, 0x0008);
    assert!(!s.enabled[2]);
    let err = b
        .arm
        .movej(&[0.0; 6], MoveOpts::speed(10), true)
        .await
        .unwrap_err();
    assert!(matches!(err, RealmanError::Rejected { .. }), "{err:?}");
}

// ---------------------------------------------------------------- real time

/// A TCP emulator on 127.0.0.1, a driver connected to it and a feed on a free UDP port the push
/// is aimed at.
async fn tcp_bench() -> Bench {
    let emu = RealmanEmulator::spawn(
        emulator_config(),
        Transport::Tcp("127.0.0.1:0".parse().unwrap()),
    )
    .await
    .expect("emulator listens");
    let addr = emu.local_addr().expect("TCP address").to_string();
    let arm = RealmanClient::connect(&addr, ClientConfig::default())
        .await
        .expect("driver connects");
    let feed = StateFeed::bind("127.0.0.1:0", JointSpeedUnit::default())
        .await
        .expect("UDP bind");
    let port = feed.local_addr().unwrap().port();
    arm.set_realtime_push(&push_to(Ipv4Addr::LOCALHOST, port, 5))
        .await
        .expect("push aimed at the feed");
    Bench { emu, arm, feed }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn over_tcp_handshake_movej_and_the_udp_push_agree() {
    let b = tcp_bench().await;
    let h = b.arm.handshake().await.expect("handshake");
    assert_eq!(h.software.product_version, "RM65-B");
    assert_eq!(h.push.ip, "127.0.0.1");
    let first = sample_where(&b.feed, Duration::from_secs(2), |_| true)
        .await
        .expect("UDP push arrives");
    assert!(max_abs_diff(&first.joints_rad, &[0.0; 6]) < 1e-9);
    b.arm
        .movej(&rad(&A_POSE_DEG), MoveOpts::speed(50), true)
        .await
        .expect("movej arrives");
    let q = b.arm.joint_positions().await.unwrap();
    assert!(at_deg(&q, &A_POSE_DEG), "{:?}", deg(&q));
    // The push may still carry a datagram sent just before the arrival; the next ones show
    // the arm idle at the target.
    let s = sample_where(&b.feed, Duration::from_secs(2), |s| {
        s.status == Some(ArmStatus::Idle)
    })
    .await
    .expect("the push shows the arm idle");
    assert!(
        at_deg(&s.joints_rad, &A_POSE_DEG),
        "{:?}",
        deg(&s.joints_rad)
    );
    // A refusal over TCP is typed the same way.
    let err = b
        .arm
        .movej(
            &rad(&[0.0, 131.0, 0.0, 0.0, 0.0, 0.0]),
            MoveOpts::speed(20),
            true,
        )
        .await
        .unwrap_err();
    assert!(
        matches!(
            err,
            RealmanError::Rejected {
                command: "movej",
                ..
            }
        ),
        "{err:?}"
    );
    // Real-time push rate at cycle 1: about 200 per second (loose: a shared machine).
    let mut rx = b.feed.subscribe();
    sleep(Duration::from_secs(1)).await;
    let mut n = 0;
    while rx.try_recv().is_ok() {
        n += 1;
    }
    assert!((100..=210).contains(&n), "{n} datagrams in 1 s");
    b.emu.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn over_tcp_two_clients_gripper_and_faults() {
    let b = tcp_bench().await;
    let addr = b.emu.local_addr().unwrap().to_string();
    let other = RealmanClient::connect(&addr, ClientConfig::default())
        .await
        .unwrap();
    let twist = rad(&[0.0, 0.0, 0.0, 0.0, 0.0, 30.0]);
    let (a, c) = tokio::join!(
        b.arm.gripper_position(300, true),
        other.movej(&twist, MoveOpts::speed(50), true)
    );
    a.expect("gripper arrives");
    c.expect("move of the other client arrives");
    assert_eq!(b.arm.gripper_state().await.unwrap().position, 300);
    let q = other.joint_positions().await.unwrap();
    assert!(at_deg(&q, &[0.0, 0.0, 0.0, 0.0, 0.0, 30.0]), "{q:?}");

    b.emu
        .inject(RealmanFault::ReplyDelay { delay_ms: 600 })
        .unwrap();
    let start = std::time::Instant::now();
    let err = b.arm.joint_positions().await.unwrap_err();
    assert!(matches!(err, RealmanError::Timeout { .. }), "{err:?}");
    let waited = start.elapsed();
    assert!(
        waited >= Duration::from_millis(500) && waited < Duration::from_millis(1500),
        "{waited:?}"
    );
    b.emu.clear(RealmanFaultKind::ReplyDelay);
    sleep(Duration::from_millis(300)).await;

    b.emu
        .inject(RealmanFault::ConnectionDrop { peer_ip: None })
        .unwrap();
    let dropped = timeout(Duration::from_secs(2), async {
        while b.arm.is_connected() || other.is_connected() {
            sleep(Duration::from_millis(5)).await;
        }
    })
    .await;
    assert!(dropped.is_ok(), "both clients notice the drop");
    b.arm.reconnect().await.expect("reconnects");
    let q = b
        .arm
        .joint_positions()
        .await
        .expect("answered after reconnect");
    assert!(at_deg(&q, &[0.0, 0.0, 0.0, 0.0, 0.0, 30.0]), "{q:?}");
    b.emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn modbus_registers_are_read_back_and_the_tool_port_excludes_the_gripper() {
    let b = virtual_bench().await;
    let arm = &b.arm;
    // No port in Modbus mode: no slave answers.
    assert!(matches!(
        arm.read_holding_register(0, 1, 100).await,
        Err(RealmanError::Rejected { .. })
    ));
    arm.set_modbus_mode(0, 115_200, 2)
        .await
        .expect("RTU on port 0");
    arm.write_registers(0, 1, 100, &[0x1234, 0xABCD])
        .await
        .expect("two registers written");
    assert_eq!(arm.read_holding_register(0, 1, 100).await.unwrap(), 0x1234);
    assert_eq!(
        arm.read_holding_register(0, 1, 101).await.unwrap(),
        0xABCDu16 as i16,
        "the controller reports registers signed"
    );
    assert_eq!(arm.read_holding_register(0, 2, 100).await.unwrap(), 0);
    // The gripper talks over the tool's RS485 port: not while it is in Modbus mode.
    arm.gripper_position(500, false)
        .await
        .expect("gripper free");
    arm.set_modbus_mode(1, 9600, 1)
        .await
        .expect("RTU on the tool port");
    assert!(matches!(
        arm.gripper_position(600, false).await,
        Err(RealmanError::Rejected { .. })
    ));
    arm.close_modbus_mode(1).await.expect("tool port back");
    arm.gripper_position(600, false)
        .await
        .expect("gripper free again");
    assert_eq!(arm.rm_plus_mode().await.unwrap(), 0);
    arm.set_rm_plus_mode(256_000)
        .await
        .expect("a known baud rate");
    assert_eq!(arm.rm_plus_mode().await.unwrap(), 256_000);
    arm.hand_follow_angle([100, 200, 300, 400, 500, 600], false)
        .await
        .expect("hand follows angles");
    arm.hand_follow_pos([0; 6], false)
        .await
        .expect("hand follows positions");
}
