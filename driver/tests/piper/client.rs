//! The Piper client against a minimal scripted arm on the virtual bus, under a paused clock.
//! The fake arm builds its frames from raw bytes (not the driver's codec) and implements only
//! what these tests need; the full emulator lives in `sim` and is exercised by the root
//! package's integration tests.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::{CanBus, CanFrame};
use driver::piper::*;
use tokio::time::{interval, Instant};

#[derive(Clone, Copy)]
struct ArmOptions {
    answer_enable: bool,
}

#[derive(Default)]
struct ArmModel {
    enabled: u8,
    ctrl_mode: u8,
    move_mode: u8,
    joints_mdeg: [i32; 6],
    target_mdeg: [i32; 6],
    received: Vec<CanFrame>,
}

fn f(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).expect("test frame")
}

fn pair(id: u16, a: i32, b: i32) -> CanFrame {
    let mut d = [0u8; 8];
    d[..4].copy_from_slice(&a.to_be_bytes());
    d[4..].copy_from_slice(&b.to_be_bytes());
    f(id, &d)
}

fn firmware_reply() -> Vec<CanFrame> {
    let mut buf = [0u8; 88];
    for (at, text) in [
        (0, "H-V1.2-1"),
        (16, "10"),
        (32, "ARM_MC"),
        (60, "S-V1.8-8"),
        (68, "250925"),
        (76, "15"),
    ] {
        buf[at..at + text.len()].copy_from_slice(text.as_bytes());
    }
    buf.chunks(8).map(|c| f(0x4AF, c)).collect()
}

/// Spawn the fake arm; returns its model for inspection.
fn spawn_arm(bus: &VirtualBus, options: ArmOptions) -> Arc<Mutex<ArmModel>> {
    let node = Arc::new(bus.attach("arm"));
    let model = Arc::new(Mutex::new(ArmModel::default()));
    let rx_node = node.clone();
    let rx_model = model.clone();
    tokio::spawn(async move {
        while let Ok(received) = rx_node.recv().await {
            let frame = received.frame;
            let d = frame.data().to_vec();
            let replies: Vec<CanFrame> = {
                let mut m = rx_model.lock().expect("model");
                m.received.push(frame);
                match frame.raw_id() {
                    0x471 if options.answer_enable => {
                        let mask = if d[0] == 7 { 0x3F } else { 1 << (d[0] - 1) };
                        if d[1] == 2 {
                            m.enabled |= mask
                        } else {
                            m.enabled &= !mask
                        }
                        vec![]
                    }
                    0x151 => {
                        m.ctrl_mode = d[0];
                        m.move_mode = d[1];
                        vec![]
                    }
                    id @ 0x155..=0x157 => {
                        let i = usize::from((id - 0x155) as u16) * 2;
                        m.target_mdeg[i] = i32::from_be_bytes([d[0], d[1], d[2], d[3]]);
                        m.target_mdeg[i + 1] = i32::from_be_bytes([d[4], d[5], d[6], d[7]]);
                        vec![]
                    }
                    0x472 if d[1] == 1 => {
                        vec![f(0x473, &[d[0], 0x05, 0xDC, 0xFA, 0x24, 0x01, 0x2C, 0])]
                    }
                    0x472 if d[1] == 2 => vec![f(0x47C, &[d[0], 0x01, 0xF4, 0, 0, 0, 0, 0])],
                    0x4AF => firmware_reply(),
                    0x477 if d[0] == 1 => {
                        vec![f(0x478, &[0x03, 0xE8, 0x03, 0xE8, 0x03, 0xE8, 0x03, 0xE8])]
                    }
                    0x477 if d[0] == 4 => vec![f(0x47E, &[100, 70, 1, 0, 0, 0, 0, 0])],
                    0x474 => vec![f(0x476, &[0x74, 0, 0, 0, 0, 0, 0, 0])],
                    0x479 => vec![f(0x476, &[0x79, 0, 0, 0, 0, 0, 0, 0])],
                    0x47A => vec![f(0x476, &[0x7A, 0, 0, 0, 0, 0, 0, 0])],
                    0x475 => vec![f(0x476, &[0x75, u8::from(d[1] == 0xAE), 0, 0, 0, 0, 0, 0])],
                    _ => vec![],
                }
            };
            for reply in replies {
                // The arm's queue is small: wait for room like a firmware would.
                while rx_node.send(reply).await.is_err() {
                    tokio::time::sleep(Duration::from_millis(1)).await;
                }
            }
        }
    });
    let tx_model = model.clone();
    tokio::spawn(async move {
        let mut tick = interval(Duration::from_millis(5));
        let mut n = 0u64;
        loop {
            tick.tick().await;
            n += 1;
            let frames = {
                let mut m = tx_model.lock().expect("model");
                let mut moving = false;
                if m.enabled == 0x3F && m.ctrl_mode == 1 {
                    for i in 0..6 {
                        let delta = (m.target_mdeg[i] - m.joints_mdeg[i]).clamp(-1000, 1000);
                        m.joints_mdeg[i] += delta;
                        moving |= delta != 0;
                    }
                }
                let j = m.joints_mdeg;
                let mut frames = vec![
                    f(
                        0x2A1,
                        &[m.ctrl_mode, 0, m.move_mode, 0, u8::from(moving), 0, 0, 0],
                    ),
                    pair(0x2A5, j[0], j[1]),
                    pair(0x2A6, j[2], j[3]),
                    pair(0x2A7, j[4], j[5]),
                ];
                if n.is_multiple_of(5) {
                    for joint in 0..6 {
                        let status = if m.enabled & (1 << joint) != 0 {
                            0x40
                        } else {
                            0
                        };
                        frames.push(f(0x261 + joint, &[0x01, 0xE0, 0, 25, 25, status, 0, 0]));
                    }
                }
                frames
            };
            for frame in frames {
                if node.send(frame).await.is_err() {
                    break;
                }
            }
        }
    });
    model
}

fn setup(options: ArmOptions) -> (VirtualBus, Arc<Mutex<ArmModel>>, Arc<dyn CanBus>) {
    let bus = VirtualBus::new(VirtualBusConfig {
        tx_queue_len: 32,
        ..VirtualBusConfig::default()
    });
    let model = spawn_arm(&bus, options);
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    (bus, model, host)
}

const ARM: ArmOptions = ArmOptions {
    answer_enable: true,
};

#[tokio::test(start_paused = true)]
async fn connect_detects_firmware_and_streams_state() {
    let (_bus, _model, host) = setup(ARM);
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    assert_eq!(
        piper.firmware_version(),
        Some(FirmwareVersion::new(1, 8, 8))
    );
    assert_eq!(
        piper.state().firmware.map(|f| f.hardware),
        Some("H-V1.2-1".to_owned())
    );
    tokio::time::sleep(Duration::from_millis(1100)).await;
    let state = piper.state();
    assert!(piper.is_ok());
    assert_eq!(state.joints_rad(), Some([0.0; 6]));
    let rate = state.link.rates_hz.get(&0x2A1).copied().unwrap_or(0.0);
    assert!((rate - 200.0).abs() < 15.0, "0x2A1 at {rate} Hz");
    let low = state.link.rates_hz.get(&0x261).copied().unwrap_or(0.0);
    assert!((low - 40.0).abs() < 5.0, "0x261 at {low} Hz");
    assert!(
        state.link.frames_per_s > 1000.0,
        "{}",
        state.link.frames_per_s
    );
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn enable_move_and_disable_are_confirmed() {
    let (_bus, model, host) = setup(ARM);
    let piper = PiperBuilder::new(host)
        .joint_limits(LimitPolicy::Reject)
        .connect()
        .await
        .expect("connect");
    piper.enable(MotorSelect::All).await.expect("enable");
    assert!(piper.state().arm_enabled());
    let target = [0.2, 0.3, -0.4, 0.1, -0.2, 0.5];
    piper.move_joints_rad(target, 50).await.expect("move");
    piper
        .wait_for_move_mode(MoveKind::J, Duration::from_millis(100))
        .await
        .expect("mode echo");
    let state = piper
        .wait_for_arrival(0.002, Duration::from_secs(5))
        .await
        .expect("arrival");
    let joints = state.joints_rad().expect("joints");
    for (j, t) in joints.iter().zip(target) {
        assert!((j - t).abs() < 0.002, "{joints:?}");
    }
    assert_eq!(
        model.lock().expect("model").target_mdeg,
        target.map(|rad: f64| (rad.to_degrees() * 1000.0).round() as i32)
    );
    piper.disable(MotorSelect::All).await.expect("disable");
    assert_eq!(piper.state().enabled_mask().0, 0);
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn queries_return_typed_replies() {
    let (_bus, _model, host) = setup(ARM);
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    let limits = piper.query_all_joint_limits().await.expect("limits");
    // The fake arm answers ±150.0° (0.1° units) and 3.00 rad/s (0.01 rad/s units).
    for (i, l) in limits.iter().enumerate() {
        assert_eq!(l.joint, i as u8 + 1);
        assert!((l.max_rad - 150f64.to_radians()).abs() < 1e-12, "{l:?}");
        assert!((l.min_rad + 150f64.to_radians()).abs() < 1e-12, "{l:?}");
        assert!((l.max_speed_rad_s - 3.0).abs() < 1e-12, "{l:?}");
    }
    let acc = piper.query_joint_max_acc(4).await.expect("acc");
    assert!((acc - 5.0).abs() < 1e-12, "{acc}");
    let end = piper.query_end_limits().await.expect("end limits");
    assert!((end.linear_m_s - 1.0).abs() < 1e-12, "{end:?}");
    assert_eq!(piper.state().end_limits, Some(end));
    let teach = piper.query_gripper_teach_params().await.expect("teach");
    assert!((teach.max_stroke_m - 0.07).abs() < 1e-12, "{teach:?}");
    piper.set_joint_max_speed(2, 2.5).await.expect("acked");
    piper
        .set_joint_zero(JointSelect::Joint(3))
        .await
        .expect("zero acked");
    // The fake arm does not answer 0x47B: a typed timeout after the query deadline.
    let start = Instant::now();
    let result = piper.query_collision_levels().await;
    assert!(
        matches!(result, Err(PiperError::Timeout { .. })),
        "{result:?}"
    );
    assert_eq!(start.elapsed(), Timeouts::default().query);
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn silent_bus_times_out_and_link_loss_flips_is_ok() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let timeouts = Timeouts {
        first_feedback: Some(Duration::from_millis(200)),
        ..Timeouts::default()
    };
    let result = PiperBuilder::new(host.clone())
        .timeouts(timeouts)
        .connect()
        .await;
    assert!(
        matches!(result, Err(PiperError::Timeout { .. })),
        "{result:?}"
    );

    let timeouts = Timeouts {
        first_feedback: None,
        ..Timeouts::default()
    };
    let piper = PiperBuilder::new(host)
        .timeouts(timeouts)
        .firmware(FirmwareSelection::Forced(FirmwareVersion::new(1, 6, 3)))
        .connect()
        .await
        .expect("connect without waiting");
    let start = Instant::now();
    let result = piper.query_firmware().await;
    assert!(
        matches!(result, Err(PiperError::Timeout { .. })),
        "{result:?}"
    );
    assert!(start.elapsed() <= timeouts.query + Duration::from_millis(1));
    assert!(!piper.is_ok());
    piper.disconnect().await;

    let (bus, _model, host) = setup(ARM);
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert!(piper.is_ok() && piper.state().link.ok);
    let silenced = Instant::now();
    bus.faults().silence_node("arm");
    let state = piper
        .wait_for(|s| !s.link.ok, Duration::from_millis(100), "link loss")
        .await
        .expect("flip");
    assert!(!state.link.ok && !piper.is_ok());
    assert!(silenced.elapsed() <= Duration::from_millis(100));
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn unconfirmed_enable_is_a_typed_timeout() {
    let (_bus, model, host) = setup(ArmOptions {
        answer_enable: false,
    });
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    let result = piper.enable(MotorSelect::Joint(2)).await;
    match result {
        Err(PiperError::EnableTimeout {
            enable: true,
            wanted,
            confirmed,
            ..
        }) => {
            assert_eq!((wanted.0, confirmed.0), (0b10, 0));
        }
        other => panic!("{other:?}"),
    }
    // The driver resent the command while waiting.
    let sent = model
        .lock()
        .expect("model")
        .received
        .iter()
        .filter(|f| f.raw_id() == 0x471)
        .count();
    assert!(sent >= 10, "{sent} enable frames");
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn limits_reject_before_sending_and_ownership_is_exclusive() {
    let (_bus, model, host) = setup(ARM);
    let piper = PiperBuilder::new(host.clone())
        .joint_limits(LimitPolicy::Reject)
        .connect()
        .await
        .expect("connect");
    let again = PiperBuilder::new(host.clone()).connect().await;
    assert!(
        matches!(again, Err(PiperError::AlreadyOwned { .. })),
        "{again:?}"
    );
    let result = piper
        .move_joints_rad([3.0, 0.0, 0.0, 0.0, 0.0, 0.0], 50)
        .await;
    match result {
        Err(PiperError::OutOfLimit {
            joint: LimitedAxis::Joint(1),
            value,
            limit,
        }) => {
            assert_eq!((value, limit), (3.0, 2.6179));
        }
        other => panic!("{other:?}"),
    }
    tokio::time::sleep(Duration::from_millis(10)).await;
    let sent = model
        .lock()
        .expect("model")
        .received
        .iter()
        .filter(|f| (0x151..=0x157).contains(&f.raw_id()))
        .count();
    assert_eq!(sent, 0);
    piper.disconnect().await;
    assert!(matches!(
        piper.emergency_stop().await,
        Err(PiperError::Disconnected)
    ));
    // Released: a new driver may take the bus.
    let piper = PiperBuilder::new(host)
        .connect()
        .await
        .expect("reconnect after release");
    assert!(piper.is_connected());
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn disconnect_stops_the_tasks_and_reconnect_restarts_them() {
    let (_bus, _model, host) = setup(ARM);
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    tokio::time::sleep(Duration::from_millis(20)).await;
    let before = piper.state().arm_status.expect("status").seq;
    piper.reconnect().await.expect("reconnect");
    tokio::time::sleep(Duration::from_millis(50)).await;
    let state = piper.state();
    assert!(state.arm_status.expect("status").seq > before + 5);
    assert_eq!(state.link.reconnects, 1);
    assert!(piper.is_ok());

    let mut messages = piper.subscribe_messages();
    let first = messages.recv().await.expect("a message");
    let second = messages.recv().await.expect("another message");
    assert!(second.seq > first.seq);

    piper.disconnect().await;
    let frozen = piper.state().arm_status.expect("status").seq;
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert_eq!(piper.state().arm_status.expect("status").seq, frozen);
    assert!(!piper.is_connected());
    assert!(matches!(
        piper.query_firmware().await,
        Err(PiperError::Disconnected)
    ));
}

#[tokio::test(start_paused = true)]
async fn a_closed_interface_is_reopened_through_the_opener() {
    let bus = VirtualBus::new(VirtualBusConfig {
        tx_queue_len: 32,
        ..VirtualBusConfig::default()
    });
    let _model = spawn_arm(&bus, ARM);
    let opened: Arc<Mutex<Vec<Arc<bus::virtual_bus::VirtualNode>>>> = Arc::default();
    let opener_bus = bus.clone();
    let opener_log = opened.clone();
    let opener: BusOpener = Arc::new(move || {
        let node = Arc::new(opener_bus.attach("host"));
        opener_log.lock().expect("log").push(node.clone());
        Ok(node as Arc<dyn CanBus>)
    });
    let piper = PiperBuilder::with_opener("virt-host", opener)
        .connect()
        .await
        .expect("connect");
    let again =
        PiperBuilder::with_opener("virt-host", Arc::new(|| Err(bus::BusError::Unsupported)))
            .connect()
            .await;
    assert!(
        matches!(again, Err(PiperError::AlreadyOwned { .. })),
        "{again:?}"
    );

    // The interface goes away under the driver.
    let first = opened.lock().expect("log")[0].clone();
    first.close().await;
    let state = piper
        .wait_for(
            |s| s.link.reconnects == 1 && s.link.ok,
            Duration::from_secs(2),
            "reopen",
        )
        .await
        .expect("reopened");
    assert_eq!(state.link.bus_fault, None);
    assert_eq!(opened.lock().expect("log").len(), 2);
    piper
        .query_joint_limits(2)
        .await
        .expect("queries work on the new endpoint");
    piper.disconnect().await;
}

fn sent(model: &Arc<Mutex<ArmModel>>, id: u16) -> Vec<Vec<u8>> {
    model
        .lock()
        .expect("model")
        .received
        .iter()
        .filter(|f| f.raw_id() == u32::from(id))
        .map(|f| f.data().to_vec())
        .collect()
}

#[tokio::test(start_paused = true)]
async fn si_arguments_and_keep_fields_reach_the_wire_as_the_spec_says() {
    let (_bus, model, host) = setup(ARM);
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    // Only the speed changes: both angle fields carry the 0x7FFF "unchanged" code.
    piper
        .set_joint_limits(
            1,
            JointLimitsUpdate {
                max_speed_rad_s: Some(1.5),
                ..JointLimitsUpdate::default()
            },
        )
        .await
        .expect("acked");
    assert_eq!(
        sent(&model, 0x474).last().map(Vec::as_slice),
        Some(&[1, 0x7F, 0xFF, 0x7F, 0xFF, 0x00, 150, 0][..])
    );
    piper
        .set_end_limits(EndLimitsUpdate {
            angular_rad_s: Some(0.8),
            ..EndLimitsUpdate::default()
        })
        .await
        .expect("acked");
    assert_eq!(
        sent(&model, 0x479).last().map(Vec::as_slice),
        Some(&[0x7F, 0xFF, 0x03, 0x20, 0x7F, 0xFF, 0x7F, 0xFF][..])
    );
    piper
        .set_collision_levels([Some(3), None, None, None, None, Some(0)])
        .await
        .expect("acked");
    assert_eq!(
        sent(&model, 0x47A).last().map(Vec::as_slice),
        Some(&[3, 0xFF, 0xFF, 0xFF, 0xFF, 0, 0, 0][..])
    );
    // 0x47D has no "keep" code: the fields left out come from the arm's current values.
    piper
        .set_gripper_teach_params(GripperTeachUpdate {
            friction: Some(5),
            ..GripperTeachUpdate::default()
        })
        .await
        .expect("sent");
    // No ack for 0x47D: give the frame time to cross the bus.
    tokio::time::sleep(Duration::from_millis(5)).await;
    assert_eq!(
        sent(&model, 0x47D).last().map(Vec::as_slice),
        Some(&[100, 70, 5, 0, 0, 0, 0, 0][..])
    );
    // S-V1.8-8 (the fake arm's firmware) uses MOVE code 0x06 for MIT; the echo matches.
    piper
        .set_move_mode(MoveKind::Mit, 30)
        .await
        .expect("mode sent");
    let state = piper
        .wait_for_move_mode(MoveKind::Mit, Duration::from_millis(50))
        .await
        .expect("echo");
    assert_eq!(
        sent(&model, 0x151).last().map(Vec::as_slice),
        Some(&[0x01, 0x06, 30, 0xAD, 0, 0, 0, 0][..])
    );
    let status = state.arm_status.expect("status").value;
    assert_eq!(status.move_mode, ActiveMove::Mit);
    assert_eq!(status.move_mode.to_string(), "m");
    assert_eq!(status.ctrl_mode.to_string(), "can");
    // A pose in m and rad becomes µm and millidegrees.
    piper
        .end_pose(Pose {
            position_m: [0.25, -0.1, 0.3],
            orientation_rad: [0.0, 90f64.to_radians(), -45f64.to_radians()],
        })
        .await
        .expect("sent");
    tokio::time::sleep(Duration::from_millis(5)).await;
    let mut pose = sent(&model, 0x152);
    pose.extend(sent(&model, 0x154));
    assert_eq!(
        pose,
        vec![
            [250_000i32.to_be_bytes(), (-100_000i32).to_be_bytes()].concat(),
            [90_000i32.to_be_bytes(), (-45_000i32).to_be_bytes()].concat(),
        ]
    );
    // Values the wire cannot carry are typed errors, and nothing is sent for them.
    let before = sent(&model, 0x474).len();
    let result = piper
        .set_joint_max_speed(1, f64::NAN)
        .await
        .map_err(|e| e.to_string());
    assert!(result.is_err(), "{result:?}");
    assert!(matches!(
        piper.set_joint_max_acc(JointSelect::All, -1.0).await,
        Err(PiperError::InvalidValue {
            field: "max_acc_rad_s2",
            ..
        })
    ));
    assert_eq!(sent(&model, 0x474).len(), before);
    piper.disconnect().await;
}

#[test]
fn status_and_flag_names_come_from_one_table() {
    assert_eq!(
        ArmStatusCode::TargetAngleOverLimit.to_string(),
        "angle_limit"
    );
    assert_eq!(
        ArmStatusCode::from_name("angle_limit"),
        Some(ArmStatusCode::TargetAngleOverLimit)
    );
    assert_eq!(ArmStatusCode::from(0x2A).to_string(), "unknown(0x2A)");
    assert_eq!(ArmStatusCode::ALL.len(), 16);
    assert_eq!(
        CtrlMode::ALL.iter().map(|m| m.to_string()).nth(1),
        Some("can".to_owned())
    );
    assert_eq!(MotionStatus::Moving.name(), Some("moving"));
    // 0x9C: bit 2 over_current, bit 3 driver_over_temp, bit 4 collision, bit 7 stall.
    assert_eq!(
        DriverStatus(0xDC).faults(),
        ["over_current", "driver_over_temp", "collision", "stall"]
    );
    assert!(DriverStatus(0xDC).names().contains(&"enabled"));
    assert_eq!(GripperStatus(0xC1).faults(), ["under_voltage"]);
    assert_eq!(DriverStatus::fault_names().count(), 7);
    assert_eq!(GripperStatus::fault_names().count(), 6);
}

/// The driver's futures can run on a multi-thread runtime (real-time mode, `tokio::spawn`).
#[allow(dead_code)]
fn futures_are_send(piper: Piper) {
    fn send<T: Send>(_: T) {}
    send(piper.enable(MotorSelect::All));
    send(piper.disable(MotorSelect::Joint(1)));
    send(piper.move_joints_rad([0.0; 6], 10));
    send(piper.wait_for_arrival(0.01, Duration::from_secs(1)));
    send(piper.wait_for(|s| s.arm_enabled(), Duration::from_secs(1), "enabled"));
    send(piper.query_all_joint_limits());
    send(piper.query_firmware());
    send(piper.mit(
        1,
        MitCommand {
            p_rad: 0.0,
            v_rad_s: 0.0,
            kp: 0.0,
            kd: 0.0,
            t_nm: 0.0,
        },
    ));
    send(piper.disconnect());
    send(piper.reconnect());
    send(
        PiperBuilder::new(Arc::new(
            VirtualBus::new(VirtualBusConfig::default()).attach("x"),
        ))
        .connect(),
    );
}
