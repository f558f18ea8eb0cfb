//! The Realman client against a scripted in-process controller built from the fixture
//! transcripts, over `tokio::io::duplex` under a paused clock.

use std::time::Duration;

use driver::realman::codec::decode::GripperMode;
use driver::realman::{
    ArmStatus, ClientConfig, Connect, ControllerError, Device, JointSpeedUnit, MoveOpts, Pose,
    RealmanClient, RealmanError, Smoothing, StateFeed,
};
use testkit::transcript::{realman_fixtures_dir, Transcript, Vector};
use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};
use tokio::sync::mpsc;
use tokio::time::Instant;

/// What the scripted controller does when a request arrives.
#[derive(Debug, Clone)]
enum Action {
    Write(String),
    Sleep(Duration),
    Close,
}

#[derive(Debug, Clone)]
struct Step {
    request: String,
    actions: Vec<Action>,
}

fn load(file: &str) -> Transcript {
    Transcript::load(realman_fixtures_dir().join(format!("{file}.jsonl"))).expect("fixture")
}

fn vector<'a>(t: &'a Transcript, name: &str) -> &'a Vector {
    t.get(name).expect("vector")
}

/// A step from a vector: the reply at once, each event after `motion` (separate writes, as the
/// controller does).
fn step(v: &Vector, motion: Duration) -> Step {
    let mut actions = Vec::new();
    for (i, r) in v.replies.iter().enumerate() {
        if i > 0 {
            actions.push(Action::Sleep(motion));
        }
        actions.push(Action::Write(r.clone()));
    }
    Step {
        request: v.request.clone(),
        actions,
    }
}

/// Runs the controller side: every CRLF-terminated request is logged and matched with the
/// first unused step with the same bytes; unmatched requests get no answer.
async fn peer(mut io: DuplexStream, mut steps: Vec<Step>, log: mpsc::UnboundedSender<String>) {
    let mut buf = Vec::new();
    let mut chunk = [0u8; 4096];
    loop {
        let Ok(n) = io.read(&mut chunk).await else {
            return;
        };
        if n == 0 {
            return;
        }
        buf.extend_from_slice(&chunk[..n]);
        while let Some(end) = buf.windows(2).position(|w| w == b"\r\n") {
            let line: Vec<u8> = buf.drain(..end + 2).collect();
            let request = String::from_utf8_lossy(&line).into_owned();
            let _ = log.send(request.clone());
            let Some(pos) = steps.iter().position(|s| s.request == request) else {
                continue;
            };
            for action in steps.remove(pos).actions {
                match action {
                    Action::Write(text) => {
                        if io.write_all(text.as_bytes()).await.is_err() {
                            return;
                        }
                    }
                    Action::Sleep(d) => tokio::time::sleep(d).await,
                    Action::Close => return,
                }
            }
        }
    }
}

async fn start(
    steps: Vec<Step>,
    config: ClientConfig,
) -> (RealmanClient, mpsc::UnboundedReceiver<String>) {
    let (ours, theirs) = tokio::io::duplex(64 * 1024);
    let (tx, rx) = mpsc::unbounded_channel();
    tokio::spawn(peer(theirs, steps, tx));
    (RealmanClient::from_stream(ours, config).await, rx)
}

fn deg(d: &[f64]) -> Vec<f64> {
    d.iter().map(|x| x.to_radians()).collect()
}

const Q1: [f64; 6] = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0];

#[tokio::test(start_paused = true)]
async fn realman_handshake_reads_the_power_on_controller() {
    let t = load("handshake");
    let steps = t.vectors.iter().map(|v| step(v, Duration::ZERO)).collect();
    let (client, mut log) = start(steps, ClientConfig::default()).await;
    let h = client.handshake().await.expect("handshake");
    assert_eq!((h.software.model, h.software.dof), (Some("RM65"), 6));
    assert_eq!(h.push.port, 8089);
    assert_eq!(h.push.period_ms, 5);
    assert_eq!(h.tool_frame.name, "Arm_Tip");
    assert!((h.joint_max_rad[2] - 135f64.to_radians()).abs() < 1e-12);
    assert!((h.joint_max_speed_rad_s[0] - 180f64.to_radians()).abs() < 1e-9);
    assert!((h.dh[0].d_m - 0.2405).abs() < 1e-12);
    // The requests went out in the SDK's order, byte for byte.
    for v in t.vectors.iter().take(11) {
        assert_eq!(log.recv().await.unwrap(), v.request);
    }
    assert!(client.power().await.unwrap());
    let s = client.arm_state().await.unwrap();
    assert!(s.errors.is_empty());
    assert!((s.pose.position_m[2] - 0.8505).abs() < 1e-9);
}

#[tokio::test(start_paused = true)]
async fn realman_pairing_survives_events_before_the_reply() {
    let m = load("motion");
    let reply = vector(&m, "get_joint_degree");
    let stale = m.get("movej_blocking").unwrap().replies[1].clone();
    let notice = "{\"state\":\"program_run_finish\",\"finish_id\":3}\r\n".to_string();
    let power = "{\"state\":\"arm_power_state\",\"power_state\":1}\r\n".to_string();
    let steps = vec![
        // The arrival event and a notice arrive before the reply to get_joint_degree.
        Step {
            request: reply.request.clone(),
            actions: vec![
                Action::Write(stale.clone()),
                Action::Write(notice),
                Action::Write(reply.replies[0].clone()),
            ],
        },
        // Two requests in flight answered in reverse order.
        Step {
            request: reply.request.clone(),
            actions: vec![],
        },
        Step {
            request: "{\"command\":\"get_arm_power_state\"}\r\n".into(),
            actions: vec![
                Action::Write(power),
                Action::Write(reply.replies[0].clone()),
            ],
        },
    ];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    let mut arrivals = client.arrivals();
    let mut notices = client.notices();
    let joints = client
        .joint_positions()
        .await
        .expect("reply paired despite the event");
    assert_eq!(joints.len(), 6);
    assert!((joints[0] - 10f64.to_radians()).abs() < 1e-12);
    let (_, a) = arrivals.recv().await.unwrap();
    assert_eq!((a.device, a.ok), (Device::Arm, true));
    assert!(notices.recv().await.is_ok());

    let (j, p) = tokio::join!(client.joint_positions(), client.power());
    assert_eq!(j.unwrap().len(), 6);
    assert!(p.unwrap());
    assert_eq!(client.malformed_count(), 0);
}

#[tokio::test(start_paused = true)]
async fn realman_stale_arrival_does_not_complete_a_new_move() {
    let m = load("motion");
    let v = vector(&m, "movej_blocking");
    let steps = vec![Step {
        request: v.request.clone(),
        actions: vec![
            // An earlier move's event, delivered late, before this move's ack.
            Action::Write(v.replies[1].clone()),
            Action::Write(v.replies[0].clone()),
            Action::Sleep(Duration::from_secs(2)),
            Action::Write(v.replies[1].clone()),
        ],
    }];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    let t0 = Instant::now();
    client
        .movej(&deg(&Q1), MoveOpts::speed(20), true)
        .await
        .expect("move");
    assert_eq!(
        t0.elapsed(),
        Duration::from_secs(2),
        "completed by its own event only"
    );
}

#[tokio::test(start_paused = true)]
async fn realman_timeout_is_exactly_500_ms_and_configurable() {
    let (client, mut log) = start(vec![], ClientConfig::default()).await;
    let t0 = Instant::now();
    let err = client.joint_positions().await.unwrap_err();
    assert_eq!(t0.elapsed(), Duration::from_millis(500));
    assert!(
        matches!(err, RealmanError::Timeout { command: "get_joint_degree", after } if after == Duration::from_millis(500)),
        "{err:?}"
    );
    assert_eq!(
        log.recv().await.unwrap(),
        "{\"command\":\"get_joint_degree\"}\r\n"
    );

    let config = ClientConfig {
        reply_timeout: Duration::from_millis(120),
        ..Default::default()
    };
    let (client, _log) = start(vec![], config).await;
    let t0 = Instant::now();
    assert!(matches!(
        client.power().await,
        Err(RealmanError::Timeout { .. })
    ));
    assert_eq!(t0.elapsed(), Duration::from_millis(120));
}

#[tokio::test(start_paused = true)]
async fn realman_late_reply_is_not_given_to_the_next_request() {
    let request = "{\"command\":\"get_joint_degree\"}\r\n".to_string();
    let reply =
        |deg: i64| format!("{{\"state\":\"joint_degree\",\"joint\":[{deg},0,0,0,0,0]}}\r\n");
    let steps = vec![
        Step {
            request: request.clone(),
            actions: vec![
                Action::Sleep(Duration::from_millis(700)),
                Action::Write(reply(1000)),
            ],
        },
        Step {
            request: request.clone(),
            actions: vec![Action::Write(reply(2000))],
        },
    ];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    assert!(matches!(
        client.joint_positions().await,
        Err(RealmanError::Timeout { .. })
    ));
    // The second request is sent at 500 ms; the first reply (1°) arrives at 700 ms, then 2°.
    let j = client.joint_positions().await.unwrap();
    assert!(
        (j[0] - 2f64.to_radians()).abs() < 1e-12,
        "got the stale reply: {j:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn realman_a_lost_reply_costs_one_request_not_a_chain() {
    let request = "{\"command\":\"get_joint_degree\"}\r\n".to_string();
    let reply = "{\"state\":\"joint_degree\",\"joint\":[0,0,0,0,0,0]}\r\n".to_string();
    let answer = |delay_ms: u64| Step {
        request: request.clone(),
        actions: vec![
            Action::Sleep(Duration::from_millis(delay_ms)),
            Action::Write(reply.clone()),
        ],
    };
    // The first request is never answered; the second is answered (after 100 ms), so the
    // client wrongly takes that reply for the late first one; the third must work again.
    let steps = vec![
        Step {
            request: request.clone(),
            actions: vec![],
        },
        answer(100),
        answer(0),
        answer(0),
    ];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    assert!(matches!(
        client.joint_positions().await,
        Err(RealmanError::Timeout { .. })
    ));
    assert!(matches!(
        client.joint_positions().await,
        Err(RealmanError::Timeout { .. })
    ));
    assert!(client.joint_positions().await.is_ok());
    assert!(client.joint_positions().await.is_ok());
}

#[tokio::test(start_paused = true)]
async fn realman_refusals_are_typed() {
    let e = load("errors");
    let steps = [
        "movej_beyond_joint_limit",
        "get_current_arm_state_after_refusal",
        "movel_unreachable",
        "set_joint_max_pos_while_enabled",
    ]
    .iter()
    .map(|n| step(vector(&e, n), Duration::ZERO))
    .collect();
    let (client, _log) = start(steps, ClientConfig::default()).await;
    let err = client
        .movej(
            &deg(&[0.0, 0.0, 0.0, 0.0, 0.0, 365.0]),
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
                key: "receive_state"
            }
        ),
        "{err:?}"
    );
    let s = client.arm_state().await.unwrap();
    assert_eq!(s.errors, vec![ControllerError::TargetBeyondJointLimit]);
    let far = Pose {
        position_m: [2.0, 0.0, 0.5],
        euler_rad: [0.0; 3],
    };
    let err = client
        .movel(&far, MoveOpts::speed(20), true)
        .await
        .unwrap_err();
    assert!(
        matches!(
            err,
            RealmanError::Rejected {
                command: "movel",
                ..
            }
        ),
        "{err:?}"
    );
    let err = client
        .set_joint_max_pos(6, 350f64.to_radians())
        .await
        .unwrap_err();
    assert!(
        matches!(
            err,
            RealmanError::Rejected {
                command: "set_joint_max_pos",
                key: "joint_max_pos"
            }
        ),
        "{err:?}"
    );
    // Invalid arguments never reach the wire.
    assert!(matches!(
        client.set_collision_stage(9).await,
        Err(RealmanError::Encode(_))
    ));
}

#[tokio::test(start_paused = true)]
async fn realman_blocking_moves_complete_on_their_events() {
    let m = load("motion");
    let e = load("errors");
    let motion = Duration::from_millis(1500);
    let steps = vec![
        step(vector(&m, "movej_blocking"), motion),
        step(vector(&m, "movej_queue_first"), motion),
        step(vector(&m, "movej_queue_last"), motion),
        step(vector(&e, "movej_motion_failed"), motion),
    ];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    let t0 = Instant::now();
    client
        .movej(&deg(&Q1), MoveOpts::speed(20), true)
        .await
        .unwrap();
    assert_eq!(t0.elapsed(), motion);

    // A queued segment does not wait; the starting one waits for the final event (two events).
    let queued = MoveOpts {
        speed_percent: 20,
        blend_percent: 10,
        connect: Connect::Queue,
    };
    let t0 = Instant::now();
    client
        .movej(&deg(&[0.0, 20.0, 30.0, 40.0, 50.0, 60.0]), queued, true)
        .await
        .unwrap();
    assert_eq!(t0.elapsed(), Duration::ZERO);
    client
        .movej(&deg(&Q1), MoveOpts::speed(20), true)
        .await
        .unwrap();
    assert_eq!(t0.elapsed(), motion * 2, "waited for trajectory_connect 0");

    let err = client
        .movej(
            &deg(&[0.0, 0.0, 90.0, 0.0, 0.0, 0.0]),
            MoveOpts::speed(20),
            true,
        )
        .await
        .unwrap_err();
    assert!(
        matches!(
            err,
            RealmanError::MotionFailed {
                command: "movej",
                device: Device::Arm
            }
        ),
        "{err:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn realman_motion_timeout_when_no_event_comes() {
    let m = load("motion");
    let v = vector(&m, "movej_blocking");
    let steps = vec![Step {
        request: v.request.clone(),
        actions: vec![Action::Write(v.replies[0].clone())],
    }];
    let config = ClientConfig {
        motion_timeout: Duration::from_secs(10),
        ..Default::default()
    };
    let (client, _log) = start(steps, config).await;
    let t0 = Instant::now();
    let err = client
        .movej(&deg(&Q1), MoveOpts::speed(20), true)
        .await
        .unwrap_err();
    assert!(
        matches!(
            err,
            RealmanError::MotionTimeout {
                command: "movej",
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(t0.elapsed(), Duration::from_secs(10));
}

#[tokio::test(start_paused = true)]
async fn realman_gripper_and_hand_block_on_their_devices() {
    let g = load("gripper_hand");
    let d = Duration::from_millis(800);
    let steps = g.vectors.iter().map(|v| step(v, d)).collect();
    let (client, _log) = start(steps, ClientConfig::default()).await;
    let s = client.gripper_state().await.unwrap();
    assert_eq!((s.mode, s.position), (GripperMode::OpenIdle, 1000));
    client.gripper_route(0, 1000).await.unwrap();
    let t0 = Instant::now();
    client.gripper_position(500, true).await.unwrap();
    client.gripper_pick(500, 200, true).await.unwrap();
    client.gripper_pick_on(500, 200, false).await.unwrap();
    client.gripper_release(500, true).await.unwrap();
    assert_eq!(t0.elapsed(), d * 3);
    client.gripper_position(800, false).await.unwrap();
    let t0 = Instant::now();
    client.hand_posture(1, true).await.unwrap();
    client.hand_sequence(2, true).await.unwrap();
    assert_eq!(t0.elapsed(), d * 2);
    client
        .hand_angles(
            [
                Some(1000),
                Some(1000),
                Some(1000),
                Some(1000),
                Some(500),
                None,
            ],
            false,
        )
        .await
        .unwrap();
    client.hand_speed(500).await.unwrap();
    client.hand_force(500).await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn realman_malformed_replies_fail_the_request_not_the_connection() {
    let m = load("motion");
    let good = vector(&m, "get_joint_degree");
    let steps = vec![
        Step {
            request: good.request.clone(),
            actions: vec![Action::Write(
                "{\"state\":\"joint_degree\",\"joint\":\"oops\"}\r\n".into(),
            )],
        },
        Step {
            request: good.request.clone(),
            actions: vec![Action::Write("this is not json\r\n".into())],
        },
        Step {
            request: good.request.clone(),
            actions: vec![Action::Write(
                "{\"state\":\"joint_degree\",\"joint\":[1,2\r\n}\r\n".into(),
            )],
        },
        step(good, Duration::ZERO),
    ];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    for _ in 0..3 {
        let err = client.joint_positions().await.unwrap_err();
        assert!(
            matches!(
                err,
                RealmanError::Malformed {
                    command: "get_joint_degree",
                    ..
                }
            ),
            "{err:?}"
        );
    }
    assert_eq!(
        client.malformed_count(),
        3,
        "undecodable: the stray text, the object cut at its CR LF and the stray closing brace after it; \
         one more decodable but mistyped"
    );
    assert!(client.is_connected());
    assert_eq!(client.joint_positions().await.unwrap().len(), 6);
}

#[tokio::test(start_paused = true)]
async fn realman_passthrough_sends_fixture_bytes_without_waiting() {
    let m = load("motion");
    let (client, mut log) = start(vec![], ClientConfig::default()).await;
    let t0 = Instant::now();
    client
        .movej_canfd(
            &deg(&[10.1, 20.0, 30.0, 40.0, 50.0, 60.0]),
            false,
            Smoothing::Raw,
        )
        .await
        .unwrap();
    client
        .movej_follow(&deg(&[10.2, 20.0, 30.0, 40.0, 50.0, 60.0]))
        .await
        .unwrap();
    assert_eq!(t0.elapsed(), Duration::ZERO);
    assert_eq!(log.recv().await.unwrap(), vector(&m, "movej_canfd").request);
    assert_eq!(
        log.recv().await.unwrap(),
        vector(&m, "movej_follow").request
    );
}

#[tokio::test(start_paused = true)]
async fn realman_disconnect_fails_pending_and_reconnect_recovers() {
    let m = load("motion");
    let good = vector(&m, "get_joint_degree");
    let steps = vec![Step {
        request: good.request.clone(),
        actions: vec![Action::Sleep(Duration::from_millis(100)), Action::Close],
    }];
    let (client, _log) = start(steps, ClientConfig::default()).await;
    let t0 = Instant::now();
    let err = client.joint_positions().await.unwrap_err();
    assert!(
        matches!(
            err,
            RealmanError::Disconnected {
                command: "get_joint_degree"
            }
        ),
        "{err:?}"
    );
    assert_eq!(
        t0.elapsed(),
        Duration::from_millis(100),
        "failed when the peer closed, not at the timeout"
    );
    assert!(!client.is_connected());
    assert!(matches!(
        client.reconnect().await,
        Err(RealmanError::NoAddress)
    ));

    let (ours, theirs) = tokio::io::duplex(4096);
    let (tx, _rx) = mpsc::unbounded_channel();
    tokio::spawn(peer(theirs, vec![step(good, Duration::ZERO)], tx));
    client.reconnect_with(ours).await;
    assert!(client.is_connected());
    assert_eq!(client.joint_positions().await.unwrap().len(), 6);
}

#[tokio::test(start_paused = true)]
async fn realman_udp_state_stream_decodes_push_vectors() {
    let p = load("push");
    let (tx, rx) = mpsc::channel(8);
    let feed = StateFeed::from_channel(rx, JointSpeedUnit::default());
    let mut samples = feed.subscribe();
    let mut watch = feed.watch();
    assert!(feed.latest().is_none());
    for name in ["udp_boot_idle", "udp_moving_legacy"] {
        tx.send(vector(&p, name).replies[0].as_bytes().to_vec())
            .await
            .unwrap();
    }
    tx.send(b"{\"state\":\"realtime_arm_joint_state\"}".to_vec())
        .await
        .unwrap();
    let first = samples.recv().await.unwrap();
    assert_eq!(first.joints_rad, vec![0.0; 6]);
    assert!((first.pose.position_m[2] - 0.8505).abs() < 1e-12);
    let second = samples.recv().await.unwrap();
    assert_eq!(second.status, Some(ArmStatus::MoveJ));
    assert!((second.joints_rad[5] - 60f64.to_radians()).abs() < 1e-12);
    assert!((second.currents_a[1] - 2.5).abs() < 1e-12);
    assert!((second.temperatures_c[0] - 35.5).abs() < 1e-12);
    watch
        .wait_for(|s| s.as_ref().is_some_and(|s| s.status.is_some()))
        .await
        .unwrap();
    drop(tx);
    tokio::time::sleep(Duration::from_millis(1)).await;
    assert_eq!(
        feed.decode_errors(),
        1,
        "the incomplete datagram is counted, not published"
    );
    assert_eq!(feed.latest().unwrap().status, Some(ArmStatus::MoveJ));
}

#[tokio::test]
async fn realman_real_tcp_and_udp_loopback() {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let m = load("motion");
    let good = vector(&m, "get_joint_degree").clone();
    tokio::spawn(async move {
        for _ in 0..2 {
            let (mut s, _) = listener.accept().await.unwrap();
            let mut buf = [0u8; 256];
            let n = s.read(&mut buf).await.unwrap();
            assert_eq!(&buf[..n], good.request.as_bytes());
            s.write_all(good.replies[0].as_bytes()).await.unwrap();
            let _ = s.read(&mut buf).await;
        }
    });
    let client = RealmanClient::connect(&addr, ClientConfig::default())
        .await
        .unwrap();
    assert_eq!(client.joint_positions().await.unwrap().len(), 6);
    client.reconnect().await.unwrap();
    assert_eq!(client.joint_positions().await.unwrap().len(), 6);

    let feed = StateFeed::bind("127.0.0.1:0", JointSpeedUnit::default())
        .await
        .unwrap();
    let target = feed.local_addr().unwrap();
    let mut watch = feed.watch();
    let sender = tokio::net::UdpSocket::bind("127.0.0.1:0").await.unwrap();
    let datagram = load("push").get("udp_moving_legacy").unwrap().replies[0].clone();
    sender.send_to(datagram.as_bytes(), target).await.unwrap();
    let got = tokio::time::timeout(Duration::from_secs(5), watch.wait_for(|s| s.is_some()))
        .await
        .expect("datagram within 5 s")
        .unwrap()
        .clone()
        .unwrap();
    assert_eq!(got.status, Some(ArmStatus::MoveJ));
}
