//! The Realman emulator's transport: framing, connection limits, disconnects, push and faults.
//! Framing and faults run in virtual time on in-memory streams; the socket tests run on real
//! TCP on 127.0.0.1 in real time.

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::json;
use sim::realman::model::ArmModel;
use sim::realman::{
    ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanFault, RealmanFaultKind,
    RealmanHandle, Transport,
};
use testkit::emulators::realman::{client, emulator, LineClient, PEER};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;

const SHORT: Duration = Duration::from_millis(500);

#[tokio::test(start_paused = true)]
async fn pretty_printed_request_is_answered() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.send("{\n\t\"command\":\t\"get_joint_degree\"\n}\r\n")
        .await;
    let reply = c.json(SHORT).await.expect("reply");
    assert_eq!(reply["state"], "joint_degree");
}

#[tokio::test(start_paused = true)]
async fn unterminated_request_is_answered() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.send(r#"{"command":"get_arm_power_state"}"#).await;
    let reply = c
        .json(SHORT)
        .await
        .expect("reply without CRLF in the request");
    assert_eq!(reply, json!({"state":"arm_power_state","power_state":1}));
}

#[tokio::test(start_paused = true)]
async fn several_requests_in_one_segment_are_answered_in_order_one_line_each() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.send(concat!(
        "{\"command\":\"get_arm_power_state\"}\r\n",
        "{\"command\":\"get_joint_degree\"}",
        "{\n \"command\": \"get_install_pose\"\n}\r\n",
    ))
    .await;
    let tags: Vec<String> = [
        c.json(SHORT).await,
        c.json(SHORT).await,
        c.json(SHORT).await,
    ]
    .into_iter()
    .map(|v| {
        v.expect("three replies")["state"]
            .as_str()
            .unwrap_or("")
            .to_owned()
    })
    .collect();
    assert_eq!(tags, ["arm_power_state", "joint_degree", "install_pose"]);
}

#[tokio::test(start_paused = true)]
async fn a_request_split_over_many_writes_is_answered_once() {
    let emu = emulator().await;
    let mut c = client(&emu);
    for byte in "{\"command\":\"get_joint_degree\"}\r\n".bytes() {
        c.send(std::str::from_utf8(&[byte]).unwrap()).await;
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
    assert_eq!(c.json(SHORT).await.expect("reply")["state"], "joint_degree");
    assert!(c.line(SHORT).await.is_none());
}

#[tokio::test(start_paused = true)]
async fn malformed_json_and_unknown_commands_get_no_reply_and_the_connection_stays_usable() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.send("{\"command\":\"get_joint_degree\"\r\n").await; // truncated
    c.send("{\"command\":get_joint_degree}\r\n").await; // not JSON
    c.send("hello\r\n").await; // junk
    c.send("{\"command\":\"no_such_command\"}\r\n").await;
    c.send("{\"no_command\":1}\r\n").await;
    c.send("{\"command\":\"movej\",\"joint\":\"x\",\"v\":\"fast\"}\r\n")
        .await; // bad fields
    let bad_fields = c
        .json(SHORT)
        .await
        .expect("a known command with bad fields is refused");
    assert_eq!(bad_fields, json!({"command":"movej","receive_state":false}));
    assert!(c.line(SHORT).await.is_none(), "nothing else is answered");
    let reply = c.ask(r#"{"command":"get_arm_power_state"}"#).await;
    assert_eq!(reply["power_state"], 1);
    let stats = emu.stats();
    assert!(stats.malformed >= 3, "{stats:?}");
    assert_eq!(stats.unknown, 2, "{stats:?}");
}

#[tokio::test(start_paused = true)]
async fn each_client_gets_its_own_replies_and_only_its_own_events() {
    let emu = emulator().await;
    let mut a = client(&emu);
    let mut b = client(&emu);
    a.send("{\"command\":\"movej\",\"joint\":[5000,0,0,0,0,0],\"v\":50,\"r\":0,\"trajectory_connect\":0}\r\n").await;
    b.send("{\"command\":\"get_arm_power_state\"}\r\n").await;
    assert_eq!(a.json(SHORT).await.unwrap()["receive_state"], true);
    assert_eq!(b.json(SHORT).await.unwrap()["state"], "arm_power_state");
    let event = a
        .json(Duration::from_secs(5))
        .await
        .expect("event to the mover");
    assert_eq!(event["state"], "current_trajectory_state");
    assert!(
        b.line(SHORT).await.is_none(),
        "the other client sees no event"
    );
}

#[tokio::test(start_paused = true)]
async fn push_goes_to_connected_hosts_every_5_ms_by_default() {
    let emu = emulator().await;
    let mut rx = emu.take_datagrams().expect("in-memory datagrams");
    let _c = client(&emu);
    tokio::time::sleep(Duration::from_millis(10)).await;
    while rx.try_recv().is_ok() {}
    tokio::time::sleep(Duration::from_secs(1)).await;
    let mut got = Vec::new();
    while let Ok(d) = rx.try_recv() {
        got.push(d);
    }
    assert!(
        (199..=201).contains(&got.len()),
        "{} datagrams in 1 s",
        got.len()
    );
    assert!(got.iter().all(|d| d.to == SocketAddr::new(PEER, 8089)));
    let first: serde_json::Value = serde_json::from_str(&got[0].payload).unwrap();
    assert_eq!(first["state"], "realtime_arm_joint_state");
    assert_eq!(first["waypoint"]["position"][2], 850500);
}

#[tokio::test(start_paused = true)]
async fn push_cycle_port_and_ip_follow_set_realtime_push() {
    let emu = emulator().await;
    let mut rx = emu.take_datagrams().unwrap();
    let mut c = client(&emu);
    let reply = c
        .ask(r#"{"command":"set_realtime_push","cycle":10,"enable":true,"port":9000,"ip":"10.0.0.7","custom":{"arm_current_status":true,"joint_speed":true}}"#)
        .await;
    assert_eq!(reply, json!({"command":"set_realtime_push","state":true}));
    tokio::time::sleep(Duration::from_millis(60)).await;
    while rx.try_recv().is_ok() {}
    tokio::time::sleep(Duration::from_secs(1)).await;
    let mut got = Vec::new();
    while let Ok(d) = rx.try_recv() {
        got.push(d);
    }
    assert!(
        (19..=21).contains(&got.len()),
        "{} datagrams at 50 ms",
        got.len()
    );
    assert!(got
        .iter()
        .all(|d| d.to == "10.0.0.7:9000".parse::<SocketAddr>().unwrap()));
    let d: serde_json::Value = serde_json::from_str(&got[0].payload).unwrap();
    assert_eq!(d["arm_current_status"], "idle");
    assert!(d["joint_status"]["joint_speed"].is_array());
    let off = c
        .ask(r#"{"command":"set_realtime_push","enable":false}"#)
        .await;
    assert_eq!(off["state"], true);
    tokio::time::sleep(Duration::from_millis(60)).await;
    while rx.try_recv().is_ok() {}
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(rx.try_recv().is_err(), "a disabled push sends nothing");
}

#[tokio::test(start_paused = true)]
async fn a_fault_value_outside_the_table_is_refused_and_changes_nothing() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let refused = emu.inject(RealmanFault::ReplyDelay { delay_ms: u64::MAX });
    assert!(refused.is_err(), "{refused:?}");
    c.send("{\"command\":\"get_joint_degree\"}\r\n").await;
    assert!(
        c.line(Duration::from_millis(100)).await.is_some(),
        "replies are not delayed"
    );
}

#[tokio::test(start_paused = true)]
async fn reply_delay_fault_delays_replies_past_the_sdk_timeout() {
    let emu = emulator().await;
    let mut c = client(&emu);
    emu.inject(RealmanFault::ReplyDelay { delay_ms: 600 })
        .unwrap();
    let start = tokio::time::Instant::now();
    c.send("{\"command\":\"get_joint_degree\"}\r\n").await;
    assert!(
        c.line(Duration::from_millis(500)).await.is_none(),
        "not within 500 ms"
    );
    assert!(
        c.line(Duration::from_millis(200)).await.is_some(),
        "but after 600 ms"
    );
    assert!(start.elapsed() >= Duration::from_millis(600));
    emu.clear(RealmanFaultKind::ReplyDelay);
    c.ask(r#"{"command":"get_joint_degree"}"#).await;
}

#[tokio::test(start_paused = true)]
async fn malformed_reply_fault_truncates_the_next_replies() {
    let emu = emulator().await;
    let mut c = client(&emu);
    emu.inject(RealmanFault::MalformedReply { count: 1 })
        .unwrap();
    c.send("{\"command\":\"get_joint_degree\"}\r\n").await;
    let cut = c.line(SHORT).await.expect("a line");
    assert!(
        serde_json::from_str::<serde_json::Value>(&cut).is_err(),
        "{cut}"
    );
    assert!(cut.starts_with("{\"state\":\"joint_degree\""));
    c.ask(r#"{"command":"get_joint_degree"}"#).await;
}

#[tokio::test(start_paused = true)]
async fn connection_drop_fault_closes_the_connections() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"get_joint_degree"}"#).await;
    emu.inject(RealmanFault::ConnectionDrop { peer_ip: None })
        .unwrap();
    assert!(
        c.closed(SHORT).await,
        "the controller closed the connection"
    );
    tokio::time::sleep(Duration::from_millis(10)).await;
    assert_eq!(emu.connections(), 0);
    let mut again = client(&emu);
    again.ask(r#"{"command":"get_joint_degree"}"#).await;
}

#[tokio::test(start_paused = true)]
async fn udp_loss_fault_drops_about_the_given_share() {
    let emu = emulator().await;
    let mut rx = emu.take_datagrams().unwrap();
    let _c = client(&emu);
    emu.inject(RealmanFault::UdpLoss { permille: 500 }).unwrap();
    tokio::time::sleep(Duration::from_secs(2)).await;
    let mut n = 0;
    while rx.try_recv().is_ok() {
        n += 1;
    }
    assert!((120..280).contains(&n), "{n} of 400 datagrams kept");
    assert!(emu
        .inject(RealmanFault::UdpLoss { permille: 1001 })
        .is_err());
}

#[tokio::test(start_paused = true)]
async fn collision_fault_aborts_the_move_with_a_false_event_and_refuses_moves_until_cleared() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"movej","joint":[60000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    emu.inject(RealmanFault::Collision).unwrap();
    let event = c.json(SHORT).await.expect("event");
    assert_eq!(
        event,
        json!({"state":"current_trajectory_state","trajectory_state":false,"device":0,"trajectory_connect":0})
    );
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    assert_eq!(state["arm_state"]["err"], json!([4109]));
    let refused = c
        .ask(r#"{"command":"movej","joint":[0,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(refused["receive_state"], false);
    c.ask(r#"{"command":"clear_system_err"}"#).await;
    let ok = c
        .ask(r#"{"command":"movej","joint":[0,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(ok["receive_state"], true);
}

#[tokio::test(start_paused = true)]
async fn joint_error_fault_shows_in_the_push_and_err_flags() {
    let emu = emulator().await;
    let mut rx = emu.take_datagrams().unwrap();
    let mut c = client(&emu);
    emu.inject(RealmanFault::JointError {
        joint: 6,
        code: 0x0008,
    })
    .unwrap();
    let flags = c.ask(r#"{"command":"get_joint_err_flag"}"#).await;
    assert_eq!(flags["err_flag"], json!([0, 0, 0, 0, 0, 8]));
    tokio::time::sleep(Duration::from_millis(20)).await;
    let mut last = None;
    while let Ok(d) = rx.try_recv() {
        last = Some(d);
    }
    let d: serde_json::Value = serde_json::from_str(&last.unwrap().payload).unwrap();
    assert_eq!(d["joint_status"]["joint_err_code"][5], 8);
    assert_eq!(d["joint_status"]["joint_en_flag"][5], 0);
    assert!(emu
        .inject(RealmanFault::JointError { joint: 7, code: 1 })
        .is_err());
}

// ---- real TCP, real time ----

async fn tcp_emulator(max_connections: usize) -> RealmanHandle {
    let mut config = EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b()));
    config.max_connections = max_connections;
    RealmanEmulator::spawn(config, Transport::Tcp("127.0.0.1:0".parse().unwrap()))
        .await
        .expect("emulator on TCP")
}

async fn tcp_client(emu: &RealmanHandle) -> LineClient<TcpStream> {
    LineClient::new(
        TcpStream::connect(emu.local_addr().unwrap())
            .await
            .expect("connect"),
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_1_mb_line_closes_only_that_connection() {
    let emu = tcp_emulator(64).await;
    let mut good = tcp_client(&emu).await;
    let mut bad = tcp_client(&emu).await;
    let junk = vec![b'x'; 1 << 20];
    // The server may close while we are still writing: a write error is expected then.
    let _ = bad.stream.write_all(b"{\"command\":\"").await;
    let _ = bad.stream.write_all(&junk).await;
    let _ = bad.stream.write_all(&junk).await;
    assert!(
        bad.closed(Duration::from_secs(5)).await,
        "oversize connection closed"
    );
    let reply = good.ask(r#"{"command":"get_arm_power_state"}"#).await;
    assert_eq!(reply["power_state"], 1);
    assert_eq!(emu.stats().oversize, 1);
    emu.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn beyond_the_connection_cap_clients_are_refused_cleanly() {
    let emu = tcp_emulator(64).await;
    let mut clients = Vec::new();
    for _ in 0..100 {
        clients.push(tcp_client(&emu).await);
    }
    let mut answered = 0;
    let mut closed = 0;
    for c in &mut clients {
        c.send("{\"command\":\"get_arm_power_state\"}\r\n").await;
    }
    for c in &mut clients {
        match c.line(Duration::from_secs(2)).await {
            Some(line) => {
                assert_eq!(line, r#"{"state":"arm_power_state","power_state":1}"#);
                answered += 1;
            }
            None => closed += 1,
        }
    }
    assert_eq!((answered, closed), (64, 36));
    assert_eq!(emu.stats().refused, 36);
    // Closing admitted clients makes room again.
    clients.clear();
    tokio::time::sleep(Duration::from_millis(200)).await;
    assert_eq!(emu.connections(), 0);
    let mut late = tcp_client(&emu).await;
    late.ask(r#"{"command":"get_joint_degree"}"#).await;
    emu.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn abrupt_disconnects_mid_reply_do_not_disturb_other_clients() {
    let emu = tcp_emulator(64).await;
    let mut steady = tcp_client(&emu).await;
    for _ in 0..20 {
        let mut rude = tcp_client(&emu).await;
        // Many requests, then vanish without reading the replies.
        let burst = "{\"command\":\"get_arm_all_state\"}\r\n".repeat(200);
        let _ = rude.stream.write_all(burst.as_bytes()).await;
        drop(rude);
    }
    for _ in 0..10 {
        let reply = steady.ask(r#"{"command":"get_joint_degree"}"#).await;
        assert_eq!(reply["state"], "joint_degree");
    }
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert_eq!(emu.connections(), 1, "the rude clients were cleaned up");
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn power_loss_aborts_the_move_and_power_on_recovers() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"movej","joint":[60000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    emu.inject(RealmanFault::PowerLoss).unwrap();
    let event = c.json(SHORT).await.expect("event");
    assert_eq!(event["trajectory_state"], false);
    let power = c.ask(r#"{"command":"get_arm_power_state"}"#).await;
    assert_eq!(power["power_state"], 0);
    let en = c.ask(r#"{"command":"get_joint_en_state"}"#).await;
    assert_eq!(en["en_state"], json!([0, 0, 0, 0, 0, 0]));
    let on = c.ask(r#"{"command":"set_arm_power","arm_power":1}"#).await;
    assert_eq!(on["arm_power"], true);
    let ok = c
        .ask(r#"{"command":"movej","joint":[0,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(ok["receive_state"], true);
}

#[tokio::test(start_paused = true)]
async fn estop_refuses_moves_until_released_and_cleared() {
    let emu = emulator().await;
    let mut c = client(&emu);
    emu.inject(RealmanFault::EStop).unwrap();
    let refused = c
        .ask(r#"{"command":"movej","joint":[10000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(refused["receive_state"], false);
    c.ask(r#"{"command":"clear_system_err"}"#).await;
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    assert_eq!(
        state["arm_state"]["err"],
        json!([4112]),
        "e-stop error stays while pressed"
    );
    emu.clear(RealmanFaultKind::EStop);
    c.ask(r#"{"command":"clear_system_err"}"#).await;
    let ok = c
        .ask(r#"{"command":"movej","joint":[10000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(ok["receive_state"], true);
}

#[tokio::test(start_paused = true)]
async fn gripper_fault_makes_gripper_commands_answer_false() {
    let emu = emulator().await;
    let mut c = client(&emu);
    emu.inject(RealmanFault::GripperFault { bits: 0x01 })
        .unwrap();
    let ack = c
        .ask(r#"{"command":"set_gripper_position","position":500,"block":true}"#)
        .await;
    assert_eq!(ack, json!({"command":"set_gripper","state":false}));
    let state = c.ask(r#"{"command":"get_gripper_state"}"#).await;
    assert_eq!(state["error"], 1);
    emu.clear(RealmanFaultKind::GripperFault);
    let ack = c
        .ask(r#"{"command":"set_gripper_position","position":500,"block":false}"#)
        .await;
    assert_eq!(ack["state"], true);
}
