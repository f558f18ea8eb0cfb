//! Realman firmware (the controller's behaviour) seen through the wire, in virtual time
//! (in-memory streams).

use std::time::Duration;

use serde_json::{json, Value};
use sim::realman::FirmwareProfile;
use testkit::emulators::realman::{client, emulator, emulator_with, err_codes, joints_deg};

const SHORT: Duration = Duration::from_millis(500);

/// Read lines until an arrival event comes (or `timeout`), returning it and what came before.
async fn wait_event<S>(
    c: &mut testkit::emulators::realman::LineClient<S>,
    timeout: Duration,
) -> (Option<Value>, Vec<Value>)
where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin,
{
    let deadline = tokio::time::Instant::now() + timeout;
    let mut others = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(tokio::time::Instant::now());
        match c.json(left).await {
            Some(v) if v["state"] == "current_trajectory_state" => return (Some(v), others),
            Some(v) => others.push(v),
            None => return (None, others),
        }
    }
}

#[tokio::test(start_paused = true)]
async fn handshake_is_answered_in_the_sdk_order_with_the_expected_tags() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let expected = [
        ("get_arm_software_info", "command", "arm_software_info"),
        (
            "get_arm_current_trajectory",
            "state",
            "arm_current_trajectory",
        ),
        ("get_realtime_push", "command", "get_realtime_push"),
        ("get_current_work_frame", "state", "current_work_frame"),
        ("get_current_tool_frame", "state", "current_tool_frame"),
        ("get_install_pose", "state", "install_pose"),
        ("get_joint_min_pos", "state", "joint_min_pos"),
        ("get_joint_max_pos", "state", "joint_max_pos"),
        ("get_joint_max_acc", "state", "joint_max_acc"),
        ("get_joint_max_speed", "state", "joint_max_speed"),
        ("get_DH_data", "command", "get_DH_data"),
    ];
    for (command, key, tag) in expected {
        let reply = c.ask(&format!(r#"{{"command":"{command}"}}"#)).await;
        assert_eq!(reply[key], tag, "{command}: {reply}");
    }
    let info = c.ask(r#"{"command":"get_arm_software_info"}"#).await;
    assert_eq!(info["Product_version"], "RM65-B");
    let push = c.ask(r#"{"command":"get_realtime_push"}"#).await;
    assert_eq!(
        (push["cycle"].as_i64(), push["port"].as_i64()),
        (Some(1), Some(8089))
    );
    assert_eq!(push["enable"], true);
    let speed = c.ask(r#"{"command":"get_joint_max_speed"}"#).await;
    // 180 °/s = 30 RPM → 30000 (0.001 RPM).
    assert_eq!(speed["joint_speed"][0], 30000);
    let dh = c.ask(r#"{"command":"get_DH_data"}"#).await;
    assert_eq!(dh["joint_1"], json!([0, 0, 240500, 0]));
    assert_eq!(dh["joint_6"][2], 144000);
    let min = c.ask(r#"{"command":"get_joint_min_pos"}"#).await;
    assert_eq!(min["min_pos"].as_array().map(Vec::len), Some(6));
}

#[tokio::test(start_paused = true)]
async fn movej_acks_then_sends_one_arrival_event_on_its_own_line_and_arrives() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.send("{\"command\":\"movej\",\"joint\":[10000,20000,30000,0,40000,0],\"v\":50,\"r\":0,\"trajectory_connect\":0}\r\n").await;
    let ack = c.line(SHORT).await.expect("ack");
    assert_eq!(ack, r#"{"command":"movej","receive_state":true}"#);
    let (event, others) = wait_event(&mut c, Duration::from_secs(10)).await;
    assert!(others.is_empty(), "unexpected lines {others:?}");
    assert_eq!(
        event.expect("arrival event"),
        json!({"state":"current_trajectory_state","trajectory_state":true,"device":0,"trajectory_connect":0})
    );
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    let q = joints_deg(&state);
    for (got, want) in q.iter().zip([10.0, 20.0, 30.0, 0.0, 40.0, 0.0]) {
        assert!((got - want).abs() < 0.05, "joints {q:?}");
    }
    assert_eq!(err_codes(&state), vec![0]);
    // Exactly one event: nothing else follows.
    assert!(c.line(Duration::from_secs(1)).await.is_none());
}

async fn assert_still<S>(c: &mut testkit::emulators::realman::LineClient<S>, before: &[f64])
where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin,
{
    tokio::time::sleep(Duration::from_millis(500)).await;
    let after = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    for (a, b) in after.iter().zip(before) {
        assert!((a - b).abs() < 0.01, "arm moved: {before:?} → {after:?}");
    }
}

#[tokio::test(start_paused = true)]
async fn beyond_joint_limit_is_refused_with_4098_and_the_arm_stays_still() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let before = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    let reply = c
        .ask(
            r#"{"command":"movej","joint":[0,200000,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#,
        )
        .await;
    assert_eq!(reply, json!({"command":"movej","receive_state":false}));
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    assert_eq!(err_codes(&state), vec![4098]);
    assert_still(&mut c, &before).await;
    assert!(wait_event(&mut c, Duration::from_secs(1)).await.0.is_none());
    // The next accepted move clears the planning error.
    let ok = c
        .ask(r#"{"command":"movej","joint":[1000,0,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(ok["receive_state"], true);
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    assert_eq!(err_codes(&state), vec![0]);
}

#[tokio::test(start_paused = true)]
async fn unreachable_pose_is_refused_with_4099_and_the_arm_stays_still() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let before = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    // 2 m away: outside the 0.61 m reach.
    let reply = c
        .ask(r#"{"command":"movel","pose":[2000000,0,300000,3141,0,0],"v":50,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(reply, json!({"command":"movel","receive_state":false}));
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    assert_eq!(err_codes(&state), vec![4099]);
    assert_still(&mut c, &before).await;
}

#[tokio::test(start_paused = true)]
async fn moves_are_refused_while_powered_off_and_accepted_after_power_on() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let off = c.ask(r#"{"command":"set_arm_power","arm_power":0}"#).await;
    assert_eq!(off, json!({"command":"set_arm_power","arm_power":true}));
    let power = c.ask(r#"{"command":"get_arm_power_state"}"#).await;
    assert_eq!(power["power_state"], 0);
    let before = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    let reply = c
        .ask(r#"{"command":"movej","joint":[10000,0,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(reply["receive_state"], false);
    assert_still(&mut c, &before).await;
    c.ask(r#"{"command":"set_arm_power","arm_power":1}"#).await;
    let reply = c
        .ask(r#"{"command":"movej","joint":[10000,0,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(reply["receive_state"], true);
}

#[tokio::test(start_paused = true)]
async fn trajectory_type_is_reported_while_moving_and_none_at_rest() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let rest = c.ask(r#"{"command":"get_arm_current_trajectory"}"#).await;
    assert_eq!(rest["type"], "none");
    c.ask(r#"{"command":"movej","joint":[60000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let moving = c.ask(r#"{"command":"get_arm_current_trajectory"}"#).await;
    assert_eq!(moving["type"], "movej");
    let j1 = moving["data"][0].as_f64().unwrap() / 1000.0;
    assert!(j1 > 0.0 && j1 < 60.0, "J1 mid-move {j1}");
    let (event, _) = wait_event(&mut c, Duration::from_secs(10)).await;
    assert_eq!(event.unwrap()["trajectory_state"], true);
    let rest = c.ask(r#"{"command":"get_arm_current_trajectory"}"#).await;
    assert_eq!(rest["type"], "none");
}

#[tokio::test(start_paused = true)]
async fn pause_holds_the_arm_and_continue_finishes_the_move() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"movej","joint":[90000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let pause = c.ask(r#"{"command":"set_arm_pause"}"#).await;
    assert_eq!(pause, json!({"command":"set_arm_pause","arm_pause":true}));
    tokio::time::sleep(Duration::from_millis(400)).await;
    let held = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    assert!(held[0] > 1.0 && held[0] < 89.0, "paused mid-way: {held:?}");
    assert_still(&mut c, &held).await;
    let traj = c.ask(r#"{"command":"get_arm_current_trajectory"}"#).await;
    assert_eq!(
        traj["type"], "movej",
        "a paused move is still the current trajectory"
    );
    let cont = c.ask(r#"{"command":"set_arm_continue"}"#).await;
    assert_eq!(cont["arm_continue"], true);
    let (event, _) = wait_event(&mut c, Duration::from_secs(10)).await;
    assert_eq!(event.unwrap()["trajectory_state"], true);
    let end = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    assert!((end[0] - 90.0).abs() < 0.05, "{end:?}");
}

#[tokio::test(start_paused = true)]
async fn stop_ends_the_move_without_an_event_and_reports_none() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"movej","joint":[90000,0,0,0,0,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let stop = c.ask(r#"{"command":"set_arm_stop"}"#).await;
    assert_eq!(stop, json!({"command":"set_arm_stop","arm_stop":true}));
    tokio::time::sleep(Duration::from_millis(200)).await;
    let traj = c.ask(r#"{"command":"get_arm_current_trajectory"}"#).await;
    assert_eq!(traj["type"], "none");
    let held = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    assert!(held[0] < 89.0, "{held:?}");
    assert!(wait_event(&mut c, Duration::from_secs(2)).await.0.is_none());
}

#[tokio::test(start_paused = true)]
async fn connected_moves_wait_for_the_zero_and_earn_one_event_each() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let a = c
        .ask(r#"{"command":"movej","joint":[20000,0,0,0,0,0],"v":50,"r":0,"trajectory_connect":1}"#)
        .await;
    assert_eq!(a["receive_state"], true);
    tokio::time::sleep(Duration::from_millis(500)).await;
    let idle = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    assert!(
        idle[0].abs() < 0.01,
        "a connected move must wait for the 0: {idle:?}"
    );
    let b = c
        .ask(r#"{"command":"movej","joint":[20000,20000,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(b["receive_state"], true);
    let (first, _) = wait_event(&mut c, Duration::from_secs(10)).await;
    assert_eq!(first.unwrap()["trajectory_connect"], 1);
    let (second, _) = wait_event(&mut c, Duration::from_secs(10)).await;
    assert_eq!(second.unwrap()["trajectory_connect"], 0);
    let end = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    assert!((end[1] - 20.0).abs() < 0.05, "{end:?}");
}

#[tokio::test(start_paused = true)]
async fn gripper_ack_is_set_gripper_and_a_blocking_move_earns_a_device_1_event() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let ack = c
        .ask(r#"{"command":"set_gripper_position","position":300,"block":true}"#)
        .await;
    assert_eq!(ack, json!({"command":"set_gripper","state":true}));
    let (event, _) = wait_event(&mut c, Duration::from_secs(5)).await;
    assert_eq!(
        event.unwrap(),
        json!({"state":"current_trajectory_state","trajectory_state":true,"device":1,"trajectory_connect":0})
    );
    let state = c.ask(r#"{"command":"get_gripper_state"}"#).await;
    assert_eq!(state["actpos"], 300);
}

#[tokio::test(start_paused = true)]
async fn motion_parameters_use_the_documented_keys() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let get = c.ask(r#"{"command":"get_arm_max_line_speed"}"#).await;
    assert_eq!(
        get,
        json!({"state":"arm_max_line_speed","arm_line_speed":250})
    );
    let set = c
        .ask(r#"{"command":"set_arm_max_line_speed","arm_line_speed":500}"#)
        .await;
    assert_eq!(
        set,
        json!({"command":"set_arm_max_line_speed","arm_line_speed":true})
    );
    let get = c.ask(r#"{"command":"get_arm_max_line_speed"}"#).await;
    assert_eq!(get["arm_line_speed"], 500);
    let init = c.ask(r#"{"command":"set_arm_init"}"#).await;
    assert_eq!(init, json!({"command":"set_arm_init","arm_init":true}));
    let acc = c.ask(r#"{"command":"get_arm_max_angular_acc"}"#).await;
    assert_eq!(
        acc,
        json!({"state":"arm_max_angular_acc","arm_angular_acc":4000})
    );
    let stage = c
        .ask(r#"{"command":"set_collision_stage","collision_stage":3}"#)
        .await;
    assert_eq!(
        stage,
        json!({"command":"set_collision_stage","collision_state":true})
    );
    let stage = c.ask(r#"{"command":"get_collision_stage"}"#).await;
    assert_eq!(
        stage,
        json!({"state":"get_collision_stage","collision_stage":3})
    );
    let bad = c
        .ask(r#"{"command":"set_collision_stage","collision_stage":9}"#)
        .await;
    assert_eq!(bad["collision_state"], false);
    let off = c
        .ask(r#"{"command":"set_joint_zero_offset","offset":[1000,-2000,3000,-4000,5000,-6000]}"#)
        .await;
    assert_eq!(
        off,
        json!({"command":"set_joint_zero_offset","set_state":true})
    );
}

#[tokio::test(start_paused = true)]
async fn old_firmware_reports_arm_err_and_sys_err() {
    let emu = emulator_with(|c| c.controller.firmware = FirmwareProfile::V1_6_5).await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"movej","joint":[0,200000,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#)
        .await;
    let state = c.ask(r#"{"command":"get_current_arm_state"}"#).await;
    let arm = &state["arm_state"];
    assert_eq!(
        (arm["arm_err"].as_i64(), arm["sys_err"].as_i64()),
        (Some(4098), Some(0))
    );
    assert!(arm.get("err").is_none());
}

#[tokio::test(start_paused = true)]
async fn save_device_info_all_writes_a_state_file_that_the_next_boot_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("realman.json");
    let p = path.clone();
    let emu = emulator_with(move |c| c.controller.state_file = Some(p)).await;
    let mut c = client(&emu);
    c.ask(r#"{"command":"set_arm_max_line_speed","arm_line_speed":400}"#)
        .await;
    let saved = c.ask(r#"{"command":"save_device_info_all"}"#).await;
    assert_eq!(
        saved,
        json!({"command":"save_device_info_all","model":true})
    );
    assert!(path.exists());
    let leftovers = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(leftovers, 1, "no temporary file left behind");
    emu.shutdown().await;
    let p = path.clone();
    let emu = emulator_with(move |c| c.controller.state_file = Some(p)).await;
    let mut c = client(&emu);
    let get = c.ask(r#"{"command":"get_arm_max_line_speed"}"#).await;
    assert_eq!(get["arm_line_speed"], 400);
}

#[tokio::test(start_paused = true)]
async fn passthrough_gets_no_reply_and_moves_the_arm() {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.send(r#"{"command":"movej_canfd","joint":[1000,0,0,0,0,0],"follow":false,"trajectory_mode":0,"radio":0}"#).await;
    c.send("\r\n").await;
    assert!(
        c.line(Duration::from_millis(300)).await.is_none(),
        "passthrough is not answered"
    );
    let q = joints_deg(&c.ask(r#"{"command":"get_current_arm_state"}"#).await);
    assert!((q[0] - 1.0).abs() < 0.05, "{q:?}");
}

/// Virtual time from the second ack to the group's final event for two connected moves.
async fn connected_pair_duration(r: i64) -> (Duration, Vec<i64>) {
    let emu = emulator().await;
    let mut c = client(&emu);
    c.ask(&format!(
        r#"{{"command":"movej","joint":[30000,0,0,0,0,0],"v":50,"r":{r},"trajectory_connect":1}}"#
    ))
    .await;
    let start = tokio::time::Instant::now();
    c.ask(
        r#"{"command":"movej","joint":[30000,30000,0,0,0,0],"v":50,"r":0,"trajectory_connect":0}"#,
    )
    .await;
    let mut connects = Vec::new();
    loop {
        let (event, _) = wait_event(&mut c, Duration::from_secs(10)).await;
        let connect = event.expect("event")["trajectory_connect"]
            .as_i64()
            .unwrap();
        connects.push(connect);
        if connect == 0 {
            return (start.elapsed(), connects);
        }
    }
}

#[tokio::test(start_paused = true)]
async fn a_blend_radius_joins_connected_moves_without_stopping() {
    let (stop_between, events_plain) = connected_pair_duration(0).await;
    let (blended, events_blended) = connected_pair_duration(80).await;
    assert_eq!(events_plain, vec![1, 0]);
    assert_eq!(events_blended, vec![1, 0]);
    assert!(
        blended + Duration::from_millis(50) < stop_between,
        "blended {blended:?} vs stopping {stop_between:?}"
    );
}

/// Largest joint change between two poses, degrees.
fn max_change_deg(a_rad: &[f64], b_rad: &[f64]) -> f64 {
    a_rad
        .iter()
        .zip(b_rad)
        .map(|(a, b)| (a - b).abs().to_degrees())
        .fold(0.0, f64::max)
}

/// The largest joint change from `from_rad` seen over `span`, sampling the ground truth every
/// 5 ms (so a transient swing counts, not only where the arm ends up), and the last pose.
async fn max_excursion_deg(
    emu: &sim::realman::RealmanHandle,
    from_rad: &[f64],
    span: Duration,
) -> (f64, Vec<f64>) {
    let step = Duration::from_millis(5);
    let mut worst = 0.0_f64;
    let mut last = from_rad.to_vec();
    for _ in 0..span.as_millis() / step.as_millis() {
        tokio::time::sleep(step).await;
        last = emu.snapshot().joints_rad;
        worst = worst.max(max_change_deg(&last, from_rad));
    }
    (worst, last)
}

#[tokio::test(start_paused = true)]
async fn joint_error_mid_move_aborts_and_the_arm_holds_where_it_stopped_until_and_after_clear() {
    let emu = emulator().await;
    let mut c = client(&emu);
    // J2, J3 and J5 (the parallel axes) all move, so every coupling between them is loaded.
    let ack = c
        .ask(r#"{"command":"movej","joint":[20000,40000,60000,0,45000,0],"v":20,"r":0,"trajectory_connect":0}"#)
        .await;
    assert_eq!(ack["receive_state"], true);
    tokio::time::sleep(Duration::from_millis(300)).await;
    let moving = emu.snapshot();
    assert!(
        moving.speeds_rad_s.iter().any(|v| v.abs() > 0.1),
        "the arm should be mid-move: {:?}",
        moving.speeds_rad_s
    );
    emu.inject(sim::realman::RealmanFault::JointError {
        joint: 3,
        code: 0x0008,
    })
    .unwrap();
    let at_fault = emu.snapshot().joints_rad;
    let (event, _) = wait_event(&mut c, SHORT).await;
    assert_eq!(
        event.expect("abort event"),
        json!({"state":"current_trajectory_state","trajectory_state":false,"device":0,"trajectory_connect":0})
    );
    let (drift, held) = max_excursion_deg(&emu, &at_fault, Duration::from_secs(2)).await;
    assert_eq!(
        emu.snapshot().enabled,
        vec![true, true, false, true, true, true]
    );
    assert!(
        drift < 0.5,
        "joints moved up to {drift:.3}° while J3 was faulted: {at_fault:?} → {held:?}"
    );
    emu.clear(sim::realman::RealmanFaultKind::JointError);
    let (drift, cleared) = max_excursion_deg(&emu, &at_fault, Duration::from_secs(2)).await;
    assert!(emu.snapshot().enabled.iter().all(|e| *e));
    assert!(
        drift < 0.5,
        "joints moved up to {drift:.3}° after the clear: {at_fault:?} → {cleared:?}"
    );
}

/// Time for a blocking MOVEJ of joint 1 from 0° to 90° at full speed, ms (virtual time).
async fn j1_movej_ms<S>(c: &mut testkit::emulators::realman::LineClient<S>, to_mdeg: i64) -> u128
where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin,
{
    let start = tokio::time::Instant::now();
    let ack = c
        .ask(&format!(
            r#"{{"command":"movej","joint":[{to_mdeg},0,0,0,0,0],"v":100,"r":0,"trajectory_connect":0}}"#
        ))
        .await;
    assert_eq!(ack["receive_state"], true);
    let (event, _) = wait_event(c, Duration::from_secs(20)).await;
    assert_eq!(event.expect("arrival")["trajectory_state"], true);
    start.elapsed().as_millis()
}

#[tokio::test(start_paused = true)]
async fn a_lower_joint_speed_limit_slows_planned_moves() {
    let emu = emulator().await;
    let mut c = client(&emu);
    let fast = j1_movej_ms(&mut c, 90_000).await;
    // Limits are written to a disabled joint only (§9): 7.5 RPM = 45 °/s.
    let off = c
        .ask(r#"{"command":"set_joint_en_state","joint_en_state":[1,0]}"#)
        .await;
    assert_eq!(off["joint_en_state"], true);
    let set = c
        .ask(r#"{"command":"set_joint_max_speed","joint_max_speed":[1,7500]}"#)
        .await;
    assert_eq!(set["joint_max_speed"], true);
    c.ask(r#"{"command":"set_joint_en_state","joint_en_state":[1,1]}"#)
        .await;
    let slow = j1_movej_ms(&mut c, 0).await;
    // Trapezoids with 540 °/s²: 90/180 + 180/540 ≈ 0.83 s; 90/45 + 45/540 ≈ 2.08 s (plus
    // settling).
    assert!((800..1000).contains(&fast), "fast move took {fast} ms");
    assert!((2050..2400).contains(&slow), "slow move took {slow} ms");
}
