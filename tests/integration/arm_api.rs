//! The vendor-neutral Arm API (`driver::arm`) against both emulators through
//! `Arc<dyn ArmInterface>`: the Realman emulator over in-memory streams and the Piper emulator
//! on the virtual bus, both under a paused clock; and the acceptance path (a JSON file in the
//! documented format → factory → a Realman arm) over real TCP/UDP on 127.0.0.1.

use std::f64::consts::PI;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{Fault, FrameFilter, VirtualBus, VirtualBusConfig};
use driver::arm::{
    create_arm_from_config, AbcErrorCode, ArmCurrentStatus, ArmError, ArmInterface, IkMode, Method,
    MoveOptions, PeripheralReadWriteParams, PiperArm, PiperArmOptions, Pose, RealmanArm,
    RealmanArmOptions, TrajectoryMode, Vendor,
};
use driver::piper::PiperBuilder;
use driver::realman::{ClientConfig, JointSpeedUnit, RealmanClient, StateFeed};
use sim::piper::{PiperConfig, PiperEmulator, PiperHandle};
use sim::realman::model::ArmModel;
use sim::realman::{ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanHandle, Transport};
use tokio::sync::mpsc;
use tokio::time::{sleep, Instant};

/// The IP the in-memory Realman client claims, and the push port aimed at it.
const PEER: Ipv4Addr = Ipv4Addr::new(192, 168, 1, 10);
const PUSH_PORT: u16 = 8089;

/// An emulator and the arm connected to it; the emulator handle keeps it running.
#[allow(dead_code)] // Held, never read: dropping them would stop the emulators.
enum Bench {
    Realman(RealmanHandle),
    Piper(VirtualBus, PiperHandle),
}

struct Case {
    arm: Arc<dyn ArmInterface>,
    _bench: Bench,
    /// A joint target inside both the controller's and the API's limits, degrees.
    target_deg: [f64; 6],
    /// A second reachable configuration, for the Cartesian moves.
    other_deg: [f64; 6],
}

async fn realman_case(period_ms: u32) -> Case {
    let emu = RealmanEmulator::spawn(
        EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b())),
        Transport::InMemory,
    )
    .await
    .expect("emulator starts");
    let mut datagrams = emu.take_datagrams().expect("in-memory datagrams");
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
    let stream = emu.connect(IpAddr::V4(PEER)).expect("in-memory connect");
    let client = RealmanClient::from_stream(stream, ClientConfig::default()).await;
    let options = RealmanArmOptions {
        enable_gripper: true,
        ..RealmanArmOptions::push_to(PEER, PUSH_PORT, period_ms)
    };
    let arm = RealmanArm::from_client("left_arm", client, feed, options);
    Case {
        arm: Arc::new(arm),
        _bench: Bench::Realman(emu),
        target_deg: [10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
        other_deg: [-15.0, 30.0, 45.0, -20.0, 60.0, 10.0],
    }
}

async fn piper_case() -> Case {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emu = PiperEmulator::spawn(Arc::new(bus.attach("piper")), PiperConfig::default())
        .expect("emulator starts");
    let piper = PiperBuilder::new(Arc::new(bus.attach("host")))
        .connect()
        .await
        .expect("driver connects");
    let arm = PiperArm::from_client("right_arm", piper, PiperArmOptions::default());
    Case {
        arm: Arc::new(arm),
        _bench: Bench::Piper(bus, emu),
        target_deg: [17.0, 34.0, -29.0, 11.0, -17.0, 23.0],
        other_deg: [-10.0, 60.0, -50.0, 5.0, 20.0, -15.0],
    }
}

async fn both() -> Vec<Case> {
    vec![realman_case(5).await, piper_case().await]
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Position (m) and rotation (rad) distance between two poses (equivalent Euler triples
/// compare equal).
fn pose_error(a: &Pose, b: &Pose) -> (f64, f64) {
    driver::arm::kinematics::pose_distance(a, b)
}

fn far_pose() -> Pose {
    // 3 m from the base: beyond the reach of both arms (RM65 0.85 m, Piper 0.65 m).
    Pose::new([3.0, 0.0, 0.2], [PI, 0.0, 0.0])
}

// ---------------------------------------------------------------- virtual time

#[tokio::test(start_paused = true)]
async fn both_backends_move_read_joints_and_round_trip_the_kinematics() {
    for c in both().await {
        let arm = &c.arm;
        let v = arm.vendor();
        arm.connect().await.expect("connect");
        arm.move_joint_position(&c.target_deg, MoveOptions::blocking(50))
            .await
            .unwrap_or_else(|e| panic!("{v}: move_joint_position: {e}"));
        let q = arm.get_joint_degree().await.expect("joints");
        assert!(max_diff(&q, &c.target_deg) < 0.25, "{v}: at {q:?}");

        // The client-side FK agrees with the pose the arm itself reports.
        sleep(Duration::from_millis(50)).await;
        let s = arm.subscribe_realtime().recv().await.unwrap();
        let fk = arm
            .forward_kinematics(&s.joint_status.joint_position)
            .await
            .unwrap();
        let (dp, dr) = pose_error(&fk, &s.ee_pose);
        assert!(
            dp < 1e-4 && dr < 1e-3,
            "{v}: FK {fk:?} vs reported {:?}",
            s.ee_pose
        );

        // FK then IK from a nearby reference gives the same pose back.
        let pose = arm.forward_kinematics(&c.target_deg).await.expect("fk");
        let reference: Vec<f64> = c.target_deg.iter().map(|d| d + 3.0).collect();
        let sol = arm
            .inverse_kinematics(&pose, &reference, IkMode::SingleStep)
            .await
            .expect("ik");
        let (dp, dr) = pose_error(&arm.forward_kinematics(&sol).await.unwrap(), &pose);
        assert!(
            dp < 1e-5 && dr < 1e-5,
            "{v}: IK round trip off by {dp} m, {dr} rad"
        );

        // A joint-space move to the pose of another configuration lands on that pose.
        let goal = arm.forward_kinematics(&c.other_deg).await.unwrap();
        arm.move_joint_pose(&goal, MoveOptions::blocking(50))
            .await
            .unwrap_or_else(|e| panic!("{v}: move_joint_pose: {e}"));
        let q = arm.get_joint_degree().await.unwrap();
        let (dp, dr) = pose_error(&arm.forward_kinematics(&q).await.unwrap(), &goal);
        assert!(
            dp < 0.003 && dr < 0.02,
            "{v}: after move_joint_pose {dp} m, {dr} rad"
        );

        // A straight line 3 cm down from there.
        let mut lower = goal;
        lower.position_m[2] -= 0.03;
        arm.move_cartesian_linear(&lower, MoveOptions::blocking(30))
            .await
            .unwrap_or_else(|e| panic!("{v}: move_cartesian_linear: {e}"));
        let q = arm.get_joint_degree().await.unwrap();
        let (dp, _) = pose_error(&arm.forward_kinematics(&q).await.unwrap(), &lower);
        assert!(dp < 0.003, "{v}: after move_cartesian_linear {dp} m");
        arm.disconnect().await;
        let e = arm.get_joint_degree().await.unwrap_err();
        assert_eq!(e.code, AbcErrorCode::NotInitialized, "{v}");
    }
}

#[tokio::test(start_paused = true)]
async fn an_unreachable_pose_gives_arm_out_of_range_on_both_vendors() {
    let mut codes = Vec::new();
    for c in both().await {
        let arm = &c.arm;
        arm.connect().await.unwrap();
        // Let the freshly enabled joints settle.
        sleep(Duration::from_millis(500)).await;
        let before = arm.get_joint_degree().await.unwrap();
        let ik = arm
            .inverse_kinematics(&far_pose(), &[0.0; 6], IkMode::IterativeSearch)
            .await
            .unwrap_err();
        let movel = arm
            .move_cartesian_linear(&far_pose(), MoveOptions::blocking(20))
            .await
            .unwrap_err();
        let movep = arm
            .move_joint_pose(&far_pose(), MoveOptions::blocking(20))
            .await
            .unwrap_err();
        codes.push((arm.vendor(), ik.code, movel.code, movep.code));
        // Refused before anything was sent: the arm has not moved.
        sleep(Duration::from_millis(500)).await;
        let after = arm.get_joint_degree().await.unwrap();
        assert!(
            max_diff(&before, &after) < 0.01,
            "{}: {before:?} -> {after:?}",
            arm.vendor()
        );
    }
    for (vendor, ik, movel, movep) in codes {
        assert_eq!(
            (ik, movel, movep),
            (
                AbcErrorCode::ArmOutOfRange,
                AbcErrorCode::ArmOutOfRange,
                AbcErrorCode::ArmOutOfRange
            ),
            "{vendor}"
        );
    }
    assert_eq!(AbcErrorCode::ArmOutOfRange.value(), -107);
}

/// States delivered during one second of (virtual) time.
async fn states_per_second(arm: &dyn ArmInterface) -> usize {
    sleep(Duration::from_millis(100)).await;
    let mut sub = arm.subscribe_realtime();
    sleep(Duration::from_secs(1)).await;
    let mut n = 0;
    while sub.try_recv().is_some() {
        n += 1;
    }
    assert_eq!(sub.missed(), 0);
    n
}

#[tokio::test(start_paused = true)]
async fn the_realtime_stream_runs_at_the_arm_rate() {
    // Realman: udp_cycle 1 → 200 samples/s, udp_cycle 4 → 50/s; Piper: its 200 Hz feedback.
    for (case, lo, hi) in [
        (realman_case(5).await, 195, 205),
        (realman_case(20).await, 48, 52),
        (piper_case().await, 190, 205),
    ] {
        case.arm.connect().await.unwrap();
        let n = states_per_second(case.arm.as_ref()).await;
        assert!(
            (lo..=hi).contains(&n),
            "{}: {n} states/s",
            case.arm.vendor()
        );
        let s = case.arm.subscribe_realtime().recv().await.unwrap();
        assert_eq!(s.name, case.arm.name());
        assert_eq!(s.joint_status.joint_position.len(), 6);
        assert_eq!(s.joint_status.joint_en_flag, vec![true; 6]);
        assert_eq!(s.joint_status.joint_speed.len(), 6);
        assert_eq!(s.arm_current_status, ArmCurrentStatus::Idle);
        assert!(
            s.since_connect >= Duration::from_secs(1),
            "{:?}",
            s.since_connect
        );
    }
}

#[tokio::test(start_paused = true)]
async fn the_callback_form_sees_the_motion() {
    for c in both().await {
        c.arm.connect().await.unwrap();
        let seen = Arc::new(AtomicUsize::new(0));
        let last_j1 = Arc::new(std::sync::Mutex::new(f64::NAN));
        let (s, l) = (seen.clone(), last_j1.clone());
        c.arm
            .realtime_arm_state_call_back(Box::new(move |state| {
                s.fetch_add(1, Ordering::SeqCst);
                *l.lock().unwrap() = state.joint_status.joint_position[0];
            }))
            .unwrap();
        c.arm
            .move_joint_position(&c.target_deg, MoveOptions::blocking(50))
            .await
            .unwrap();
        sleep(Duration::from_millis(100)).await;
        let n = seen.load(Ordering::SeqCst);
        let j1 = *last_j1.lock().unwrap();
        assert!(n > 50, "{}: {n} callbacks", c.arm.vendor());
        assert!(
            (j1 - c.target_deg[0]).abs() < 0.25,
            "{}: last J1 {j1}",
            c.arm.vendor()
        );
    }
}

#[tokio::test(start_paused = true)]
async fn the_gripper_opens_closes_and_reports_on_both_vendors() {
    for c in both().await {
        let arm = &c.arm;
        let v = arm.vendor();
        arm.connect().await.unwrap();
        arm.set_gripper_position(500, true, 10)
            .await
            .unwrap_or_else(|e| panic!("{v}: position: {e}"));
        let g = arm.get_gripper_state().await.expect("gripper state");
        assert!((g.actpos - 500).abs() <= 15, "{v}: {g:?}");
        arm.set_gripper_release(500, true, 10).await.unwrap();
        let open = arm.get_gripper_state().await.unwrap().actpos;
        arm.set_gripper_pick(500, 300, true, 10).await.unwrap();
        let closed = arm.get_gripper_state().await.unwrap().actpos;
        assert!(
            open > 950 && closed < 50,
            "{v}: open {open}, closed {closed}"
        );
        let e = arm.set_gripper_pick(500, 20, true, 10).await.unwrap_err();
        assert_eq!(e.code, AbcErrorCode::ParamOutOfRange, "{v}: force 20");
    }
}

/// Calls `method` with valid arguments; `Ok(())` or the error it gave.
async fn call(arm: &dyn ArmInterface, method: Method) -> Result<(), ArmError> {
    let q = [0.0; 6];
    let pose = arm.forward_kinematics(&q).await.unwrap_or_default();
    let o = MoveOptions::non_blocking(10);
    let raw = TrajectoryMode::Passthrough;
    match method {
        Method::Connect => arm.connect().await,
        Method::MoveJointPosition => arm.move_joint_position(&q, o).await,
        Method::MoveCartesianLinear => arm.move_cartesian_linear(&pose, o).await,
        Method::MoveJointPose => arm.move_joint_pose(&pose, o).await,
        Method::MoveJointPositionCanfd => arm.move_joint_position_canfd(&q, false, raw).await,
        Method::MoveCartesianPoseCanfd => arm.move_cartesian_pose_canfd(&pose, false, raw).await,
        Method::MoveJointFollow => arm.move_joint_follow(&q).await,
        Method::MovePoseFollow => arm.move_pose_follow(&pose).await,
        Method::RealtimeState => arm.subscribe_realtime().recv().await.map(drop),
        Method::SetArmSlowStop => arm.set_arm_slow_stop().await,
        Method::SetArmStop => arm.set_arm_stop().await,
        Method::SetArmPause => arm.set_arm_pause().await,
        Method::SetArmContinue => arm.set_arm_continue().await,
        Method::SetPlusMode => arm.set_plus_mode(115_200).await,
        Method::SetGripperRelease => arm.set_gripper_release(500, false, 0).await,
        Method::SetGripperPick => arm.set_gripper_pick(500, 200, false, 0).await,
        Method::SetGripperPickOn => arm.set_gripper_pick_on(500, 200, false, 0).await,
        Method::SetGripperPosition => arm.set_gripper_position(500, false, 0).await,
        Method::GetGripperState => arm.get_gripper_state().await.map(drop),
        Method::SetHandPosture => arm.set_hand_posture(1, false, 0).await,
        Method::SetHandAngle => arm.set_hand_angle([100, -1, 100, 100, 100, 100]).await,
        Method::SetHandFollowAngle => arm.set_hand_follow_angle([0; 6], 0).await,
        Method::SetHandFollowPos => arm.set_hand_follow_pos([0; 6], 0).await,
        Method::SetHandSpeed => arm.set_hand_speed(500).await,
        Method::SetHandForce => arm.set_hand_force(500).await,
        Method::GetJointDegree => arm.get_joint_degree().await.map(drop),
        Method::ForwardKinematics => arm.forward_kinematics(&q).await.map(drop),
        Method::InverseKinematics => arm
            .inverse_kinematics(&pose, &q, IkMode::SingleStep)
            .await
            .map(drop),
        Method::SetModbusMode => arm.set_modbus_mode(1, 115_200, 2).await,
        Method::CloseModbusMode => arm.close_modbus_mode(1).await,
        Method::WriteRegisters => {
            let p = PeripheralReadWriteParams {
                port: 1,
                address: 0,
                device: 1,
                num: 1,
            };
            // The port is back out of Modbus mode (CloseModbusMode ran before): open it again.
            arm.set_modbus_mode(1, 115_200, 2).await?;
            arm.write_registers(&p, &[1]).await?;
            arm.close_modbus_mode(1).await
        }
        Method::GetErrorFlag => arm.get_error_flag().await.map(drop),
    }
}

#[tokio::test(start_paused = true)]
async fn the_capability_table_is_exactly_what_answers() {
    for c in both().await {
        let arm = c.arm.as_ref();
        arm.connect().await.unwrap();
        // The state stream must have started for the feedback-based methods.
        arm.subscribe_realtime().recv().await.unwrap();
        for method in Method::ALL {
            let result = call(arm, method).await;
            let v = arm.vendor();
            if arm.supports(method) {
                assert!(result.is_ok(), "{v}: {} failed: {result:?}", method.name());
            } else {
                let e = result.expect_err(method.name());
                assert_eq!(
                    e.code,
                    AbcErrorCode::NotImplemented,
                    "{v}: {}: {e}",
                    method.name()
                );
                assert_eq!(e.value(), -6);
            }
            // Let a stop settle before the next call.
            if matches!(method, Method::SetArmStop | Method::SetArmSlowStop) {
                sleep(Duration::from_millis(300)).await;
            }
        }
    }
}

#[tokio::test(start_paused = true)]
async fn the_piper_lacks_pause_and_the_hand() {
    let c = piper_case().await;
    c.arm.connect().await.unwrap();
    for e in [
        c.arm.set_arm_pause().await.unwrap_err(),
        c.arm.set_hand_posture(3, true, 5).await.unwrap_err(),
        c.arm
            .move_joint_position(
                &c.target_deg,
                MoveOptions {
                    trajectory_connect: true,
                    ..MoveOptions::blocking(20)
                },
            )
            .await
            .unwrap_err(),
    ] {
        assert_eq!(e.code, AbcErrorCode::NotImplemented, "{e}");
    }
    assert_eq!(c.arm.vendor(), Vendor::Piper);
}

// ---------------------------------------------------------------- real time

fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("free UDP port")
        .port()
}

fn write_config(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).expect("write config");
    path
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_config_file_in_the_documented_format_drives_the_emulator_over_tcp() {
    let emu = RealmanEmulator::spawn(
        EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b())),
        Transport::Tcp("127.0.0.1:0".parse().unwrap()),
    )
    .await
    .expect("emulator listens");
    let port = emu.local_addr().expect("TCP address").port();
    let udp_port = free_udp_port();
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        r#"{{
    "arm_type": "realman",
    "arm_name": "left_arm",
    "ip": "127.0.0.1",
    "port": "{port}",
    "udp_ip": "127.0.0.1",
    "udp_port": "{udp_port}",
    "udp_cycle": "2",
    "enable_gripper": "true"
}}"#
    );
    let path = write_config(&dir, "arm.json", &text);
    let arm = create_arm_from_config(&path).expect("arm from config");
    assert_eq!((arm.vendor(), arm.name()), (Vendor::Realman, "left_arm"));
    arm.connect().await.expect("connect over TCP");

    let mut sub = arm.subscribe_realtime();
    let first = tokio::time::timeout(Duration::from_secs(2), sub.recv())
        .await
        .expect("a pushed state within 2 s")
        .unwrap();
    assert_eq!(first.name, "left_arm");

    let target = [0.0, 25.0, 60.0, 0.0, 90.0, 0.0];
    arm.move_joint_position(&target, MoveOptions::blocking(60))
        .await
        .expect("blocking move");
    let q = arm.get_joint_degree().await.unwrap();
    assert!(max_diff(&q, &target) < 0.02, "{q:?}");
    arm.set_gripper_position(300, true, 5)
        .await
        .expect("gripper");

    // udp_cycle 2 → one state every 10 ms: about 100 in a second (loose: a shared machine).
    let mut sub = arm.subscribe_realtime();
    sleep(Duration::from_secs(1)).await;
    let mut n = 0;
    let mut last = None;
    while let Some(s) = sub.try_recv() {
        n += 1;
        last = Some(s);
    }
    assert!((50..=110).contains(&n), "{n} states in 1 s at udp_cycle 2");
    let last = last.unwrap();
    assert!(max_diff(&last.joint_status.joint_position, &target) < 0.02);
    let g = last
        .gripper_state
        .expect("the gripper is polled when enabled");
    assert!((g.actpos - 300).abs() <= 15, "{g:?}");
    arm.disconnect().await;
    emu.shutdown().await;
}

#[test]
fn config_file_errors_name_the_file_the_key_and_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let full = r#"{"arm_type": "realman", "arm_name": "a", "ip": "127.0.0.1", "port": "8080",
        "udp_ip": "127.0.0.1", "udp_port": "8089", "udp_cycle": "1", "enable_gripper": "false"}"#;
    let missing = write_config(
        &dir,
        "missing.json",
        &full.replace(r#""udp_cycle": "1","#, ""),
    );
    let e = create_arm_from_config(&missing).err().expect("missing key");
    assert_eq!(e.code, AbcErrorCode::ParamError);
    assert!(
        e.message.contains("missing.json") && e.message.contains("\"udp_cycle\""),
        "{e}"
    );

    let bad = write_config(&dir, "bad.json", &full.replace("\"8080\"", "\"eighty\""));
    let e = create_arm_from_config(&bad).err().expect("bad value");
    assert_eq!(e.code, AbcErrorCode::ParamError);
    assert!(
        e.message.contains("\"port\"") && e.message.contains("\"eighty\""),
        "{e}"
    );

    let vendor = write_config(&dir, "vendor.json", &full.replace("realman", "abb"));
    let e = create_arm_from_config(&vendor)
        .err()
        .expect("unknown vendor");
    assert_eq!(e.code, AbcErrorCode::InvalidArgument);

    let gone = dir.path().join("absent.json");
    let e = create_arm_from_config(&gone).err().expect("no file");
    assert!(e.message.contains("absent.json"), "{e}");
}

#[tokio::test(start_paused = true)]
async fn realman_refusals_pause_and_reconnect_map_to_their_codes() {
    let c = realman_case(5).await;
    let arm = c.arm.as_ref();
    let e = arm.get_joint_degree().await.unwrap_err();
    assert_eq!(e.code, AbcErrorCode::NotInitialized);
    arm.connect().await.unwrap();
    arm.connect().await.expect("connect twice is a no-op");

    // J2 131° is beyond the RM65-B's ±130°: the controller answers false.
    let e = arm
        .move_joint_position(&[0.0, 131.0, 0.0, 0.0, 0.0, 0.0], MoveOptions::blocking(20))
        .await
        .unwrap_err();
    assert_eq!(e.code, AbcErrorCode::ArmCtrlFalse, "{e}");
    let e = arm
        .move_joint_position(&[0.0; 5], MoveOptions::blocking(20))
        .await
        .unwrap_err();
    assert_eq!(e.code, AbcErrorCode::InvalidArgument, "{e}");
    let e = arm
        .move_joint_position(&[0.0; 6], MoveOptions::blocking(0))
        .await
        .unwrap_err();
    assert_eq!(e.code, AbcErrorCode::ParamOutOfRange, "{e}");

    // Pause holds the arm part way; continue finishes the move.
    let mut sub = arm.subscribe_realtime();
    arm.move_joint_position(&c.target_deg, MoveOptions::non_blocking(20))
        .await
        .unwrap();
    sleep(Duration::from_millis(500)).await;
    arm.set_arm_pause().await.unwrap();
    sleep(Duration::from_millis(200)).await;
    let held = arm.get_joint_degree().await.unwrap();
    sleep(Duration::from_millis(500)).await;
    assert!(max_diff(&held, &arm.get_joint_degree().await.unwrap()) < 0.01);
    assert!(max_diff(&held, &c.target_deg) > 1.0, "paused at {held:?}");
    while sub.try_recv().is_some() {}
    let s = sub.recv().await.unwrap();
    assert_eq!(s.arm_current_status, ArmCurrentStatus::Paused);
    arm.set_arm_continue().await.unwrap();
    let arrived = tokio::time::timeout(Duration::from_secs(30), async {
        loop {
            let s = sub.recv().await.unwrap();
            if s.arm_current_status == ArmCurrentStatus::Idle {
                return s;
            }
        }
    })
    .await
    .expect("idle again after continue");
    assert!(max_diff(&arrived.joint_status.joint_position, &c.target_deg) < 0.02);

    // A client handed in is used once: after disconnect there is nothing to reconnect with.
    arm.disconnect().await;
    assert_eq!(
        arm.connect().await.unwrap_err().code,
        AbcErrorCode::InvalidHandle
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn nothing_listening_is_a_send_failure_naming_the_address() {
    // A port that was free a moment ago: nothing accepts on it.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .unwrap()
        .port();
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        r#"{{"arm_type": "realman", "arm_name": "a", "ip": "127.0.0.1", "port": "{port}",
            "udp_ip": "127.0.0.1", "udp_port": "0", "udp_cycle": "1"}}"#
    );
    let arm = create_arm_from_config(write_config(&dir, "arm.json", &text)).unwrap();
    let e = arm.connect().await.unwrap_err();
    assert_eq!(e.code, AbcErrorCode::ArmDataSendFailed, "{e}");
    assert!(e.message.contains(&format!("127.0.0.1:{port}")), "{e}");
}

#[tokio::test(start_paused = true)]
async fn a_stopped_piper_refuses_blocking_moves_with_arm_error() {
    let c = piper_case().await;
    let arm = c.arm.as_ref();
    arm.connect().await.unwrap();
    arm.move_joint_position(&c.target_deg, MoveOptions::non_blocking(20))
        .await
        .unwrap();
    sleep(Duration::from_millis(300)).await;
    arm.set_arm_stop().await.unwrap();
    sleep(Duration::from_millis(100)).await;
    let mut sub = arm.subscribe_realtime();
    assert_eq!(
        sub.recv().await.unwrap().arm_current_status,
        ArmCurrentStatus::Stopped
    );
    let e = arm
        .move_joint_position(&[0.0; 6], MoveOptions::blocking(20))
        .await
        .unwrap_err();
    assert_eq!(e.code, AbcErrorCode::ArmError, "{e}");
}

#[tokio::test(start_paused = true)]
async fn a_piper_whose_link_is_cut_times_out_at_once_not_after_the_motion_timeout() {
    let c = piper_case().await;
    let Bench::Piper(bus, _) = &c._bench else {
        panic!("a Piper bench")
    };
    c.arm.connect().await.expect("connect");
    bus.faults().inject(Fault::drop(FrameFilter::All));
    sleep(Duration::from_millis(50)).await;
    let start = Instant::now();
    let e = c
        .arm
        .move_joint_position(&c.target_deg, MoveOptions::blocking(50))
        .await
        .expect_err("no arm answers");
    assert_eq!(e.code, AbcErrorCode::ArmTimeout, "{e}");
    assert!(
        start.elapsed() < Duration::from_secs(1),
        "gave up after {:?}, not within the 100 ms feedback timeout",
        start.elapsed()
    );
    let e = c.arm.get_joint_degree().await.expect_err("stale feedback");
    assert_eq!(e.code, AbcErrorCode::ArmTimeout, "{e}");
}

#[tokio::test(start_paused = true)]
async fn realman_peripheral_arguments_out_of_range_are_param_out_of_range() {
    let c = realman_case(5).await;
    c.arm.connect().await.expect("connect");
    let codes = [
        c.arm.set_plus_mode(1).await.expect_err("no such mode").code,
        c.arm
            .set_modbus_mode(0, 19_200, 1)
            .await
            .expect_err("no such baud rate")
            .code,
        c.arm
            .write_registers(
                &PeripheralReadWriteParams {
                    port: 0,
                    address: 0,
                    device: 1,
                    num: 11,
                },
                &[0; 11],
            )
            .await
            .expect_err("more than 10 registers")
            .code,
    ];
    assert_eq!(codes, [AbcErrorCode::ParamOutOfRange; 3]);
    let e = c.arm.close_modbus_mode(3).await.expect_err("Modbus TCP");
    assert_eq!(e.code, AbcErrorCode::NotImplemented, "{e}");
}
