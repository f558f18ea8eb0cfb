//! The emulators served over socketcand by the `armhil` binary, reached by our drivers through
//! the socketcand client: `armhil sim … --socketcand` and `armhil run --socketcand`.

use std::process::Command;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bus::socketcand::SocketcandBus;
use bus::CanBus;
use driver::robstride::{DriverConfig, Model, RobstrideDriver, RunMode};

use super::support::{free_port, listens, start_sim, Sim, ARMHIL};

#[test]
fn armhil_run_drives_the_piper_emulator_over_socketcand() {
    let (_sim, addr) = start_sim(&["piper"]);
    let out = tempfile::tempdir().expect("temp dir");
    let root = env!("CARGO_MANIFEST_DIR");
    let output = Command::new(ARMHIL)
        .args(["run", "-j", "1", "--socketcand", &addr, "--out"])
        .arg(out.path())
        .arg(format!("{root}/scenarios/piper/enable_disable.yaml"))
        .arg(format!("{root}/scenarios/piper/move_j_basic.yaml"))
        .output()
        .expect("armhil run starts");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}");
    assert!(stdout.contains("2 passed, 0 failed"), "{stdout}");
    // The recorder (a second connection) saw the driver's commands and the arm's feedback.
    let log = std::fs::read_to_string(out.path().join("move_j_basic/bus.log")).expect("bus.log");
    assert!(
        log.contains(" 155#"),
        "no MOVE J command 0x155 in the recording"
    );
    assert!(
        log.contains(" 2A5#"),
        "no joint feedback 0x2A5 in the recording"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_robstride_driver_reaches_the_emulator_over_socketcand() {
    let (_sim, addr) = start_sim(&["robstride", "--motor", "5:RS00"]);
    let host: Arc<dyn CanBus> = Arc::new(SocketcandBus::connect(&addr, "can0").await.unwrap());
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let motor = driver.motor(5, Model::RS00).unwrap();
    motor.device_id().await.unwrap();
    motor.switch_mode(RunMode::Velocity).await.unwrap();
    motor.set_velocity(3.0, 10.0, 10.0).await.unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let feedback = motor.poll().await.unwrap();
        assert_eq!(feedback.motor_id, 5);
        if (feedback.speed_rad_s - 3.0).abs() < 0.1 {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "never reached 3 rad/s: {feedback:?}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// `armhil sim robot`: the 6-DoF arm's two buses are two socketcand channels; our driver on
/// each moves its joints in CSP, and the shoulder (can0) carries the wrist (can1).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_answers_on_each_of_its_buses_over_socketcand_channels() {
    let root = env!("CARGO_MANIFEST_DIR");
    let file = format!("{root}/robots/robstride_arm6.yaml");
    let (_sim, addr) = start_sim(&["robot", &file]);
    let mut drivers = Vec::new();
    for bus in ["can0", "can1"] {
        let host: Arc<dyn CanBus> = Arc::new(SocketcandBus::connect(&addr, bus).await.unwrap());
        drivers.push(RobstrideDriver::new(host, DriverConfig::default()));
    }
    let shoulder = drivers[0].motor(2, Model::RS04).unwrap();
    let wrist = drivers[1].motor(5, Model::RS02).unwrap();
    // Motor 5 is on can1 only: can0 has no one answering to it.
    let stranger = drivers[0].motor(5, Model::RS02).unwrap();
    assert!(stranger.device_id().await.is_err(), "id 5 answered on can0");
    for (motor, target) in [(&shoulder, 0.6f32), (&wrist, -0.4)] {
        motor.switch_mode(RunMode::CyclicPosition).await.unwrap();
        motor.enable().await.unwrap();
        motor.set_position(target, 2.0).await.unwrap();
    }
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (s, w) = (shoulder.poll().await.unwrap(), wrist.poll().await.unwrap());
        if (s.angle_rad - 0.6).abs() < 0.01 && (w.angle_rad + 0.4).abs() < 0.01 {
            // Holding the arm tilted 0.6 rad forward takes torque; the wrist carries little.
            assert!(s.torque_nm.abs() > 3.0, "shoulder {s:?}");
            assert!(w.torque_nm.abs() < 2.0, "wrist {w:?}");
            break;
        }
        assert!(Instant::now() < deadline, "never got there: {s:?} {w:?}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// `armhil sim rig`: a leader Piper and its follower that name the same socketcand address
/// are on one bus behind one server, as on a shared SocketCAN interface: one client sees the
/// leader's control frames (0x155) and the follower's feedback (0x2A5) on the same connection,
/// and a second address of the rig is a bus of its own.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rig_devices_naming_one_socketcand_address_share_its_bus() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (shared, alone) = (free_port(), free_port());
    let file = dir.path().join("bimanual.yaml");
    std::fs::write(
        &file,
        format!(
            "devices:\n\
             \x20 leader: {{kind: piper, socketcand: {shared}, role: leader}}\n\
             \x20 follower: {{kind: piper, socketcand: {shared}}}\n\
             \x20 other: {{kind: piper, socketcand: {alone}}}\n"
        ),
    )
    .unwrap();
    let mut child = Sim(Command::new(ARMHIL)
        .args(["sim", "rig"])
        .arg(&file)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("armhil sim rig starts"));
    let deadline = Instant::now() + Duration::from_secs(20);
    for port in [shared, alone] {
        while !listens(("127.0.0.1", port)) {
            assert!(Instant::now() < deadline, "nothing listens on {port}");
            assert!(child.0.try_wait().unwrap().is_none(), "the rig exited");
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }
    let ids_on = |port: u16| async move {
        let bus = SocketcandBus::connect(&format!("127.0.0.1:{port}"), "can0")
            .await
            .unwrap();
        let mut ids = std::collections::BTreeSet::new();
        let until = Instant::now() + Duration::from_secs(2);
        while Instant::now() < until {
            if let Ok(Ok(frame)) =
                tokio::time::timeout(Duration::from_millis(100), bus.recv()).await
            {
                ids.insert(frame.frame.raw_id());
            }
        }
        ids
    };
    let both = ids_on(shared).await;
    assert!(both.contains(&0x155), "no leader frame: {both:x?}");
    assert!(both.contains(&0x2A5), "no follower feedback: {both:x?}");
    let other = ids_on(alone).await;
    assert!(other.contains(&0x2A5), "{other:x?}");
    assert!(
        !other.contains(&0x155),
        "the leader leaked onto another server's bus"
    );
    let _ = child.0.kill();
}

/// `armhil sim damiao` over socketcand: a host's raw enable (`FF … FF FC` on ESC_ID 1) gets
/// the motor's feedback on its MST_ID 0x11 (state 1, ESC_ID nibble 1), and our Damiao driver
/// runs the second motor, which answers on the feedback id its `--motor` gave it, in velocity
/// mode until it turns at the speed asked.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_damiao_motors_answer_a_host_over_socketcand() {
    use bus::CanFrame;
    use driver::damiao::{ControlMode, DamiaoDriver, MotorState};

    let (_sim, addr) = start_sim(&["damiao", "--motor", "1:DM4310", "--motor", "2:DM4340:0x22"]);
    let host = SocketcandBus::connect(&addr, "can0").await.unwrap();
    let enable =
        CanFrame::standard(0x001, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]).unwrap();
    host.send(enable).await.unwrap();
    let deadline = Instant::now() + Duration::from_secs(5);
    let feedback = loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let received = tokio::time::timeout(left, host.recv())
            .await
            .expect("a feedback frame within 5 s")
            .unwrap();
        if received.frame.raw_id() == 0x011 {
            break received.frame;
        }
    };
    assert_eq!(feedback.len(), 8, "{feedback}");
    assert_eq!(
        feedback.data()[0],
        0x11,
        "state 1, ESC_ID nibble 1: {feedback}"
    );

    let bus: Arc<dyn CanBus> = Arc::new(SocketcandBus::connect(&addr, "can0").await.unwrap());
    let config = driver::damiao::DriverConfig {
        // A loaded two-core machine: the loopback round trip, not the firmware, is the wait.
        timeout: Duration::from_millis(500),
        ..Default::default()
    };
    let driver = DamiaoDriver::new(bus, config);
    let motor = driver
        .motor(2, 0x22, driver::damiao::Model::DM4340)
        .unwrap();
    motor.set_control_mode(ControlMode::Velocity).await.unwrap();
    assert_eq!(motor.enable().await.unwrap().state, MotorState::Enabled);
    motor.velocity(3.0).await.unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let feedback = motor.refresh().await.unwrap();
        assert_eq!(feedback.motor, 2);
        if (feedback.velocity_rad_s - 3.0).abs() < 0.1 {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "never reached 3 rad/s: {feedback:?}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// `armhil sim damiao --state-file`: a host moves motor 1 to ESC_ID 5 and saves; after a
/// restart (the first process killed, as a power cut) the motor answers at 5, not at 1.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sim_damiao_keeps_a_saved_esc_id_in_its_state_file_across_restarts() {
    use driver::damiao::{DamiaoDriver, DriverConfig, Model as DmModel, Register, RegisterValue};

    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("dm.json");
    let file_arg = file.to_str().unwrap();
    let args = ["damiao", "--motor", "1:DM4310", "--state-file", file_arg];
    let config = DriverConfig {
        timeout: Duration::from_millis(500),
        ..Default::default()
    };
    {
        let (_sim, addr) = start_sim(&args);
        let bus: Arc<dyn CanBus> = Arc::new(SocketcandBus::connect(&addr, "can0").await.unwrap());
        let driver = DamiaoDriver::new(bus, config.clone());
        let motor = driver.motor(1, 0x11, DmModel::DM4310).unwrap();
        motor
            .write_register(Register::EscId, RegisterValue::U32(5))
            .await
            .unwrap();
        drop(motor);
        let moved = driver.motor(5, 0x11, DmModel::DM4310).unwrap();
        moved.save().await.unwrap();
        let deadline = Instant::now() + Duration::from_secs(5);
        while !file.exists() {
            assert!(Instant::now() < deadline, "the save never reached the file");
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }
    let saved = std::fs::read_to_string(&file).unwrap();
    assert!(saved.contains("\"kind\": \"damiao\""), "{saved}");
    let (_sim, addr) = start_sim(&args);
    let bus: Arc<dyn CanBus> = Arc::new(SocketcandBus::connect(&addr, "can0").await.unwrap());
    let driver = DamiaoDriver::new(bus, config);
    let moved = driver.motor(5, 0x11, DmModel::DM4310).unwrap();
    assert_eq!(moved.refresh().await.unwrap().motor, 5);
    drop(moved);
    let old = driver.motor(1, 0x11, DmModel::DM4310).unwrap();
    assert!(
        old.refresh().await.is_err(),
        "nobody answers at ESC_ID 1 any more"
    );
}

/// `armhil sim damiao --ui`: the web view's state names each motor (ids, model, mode, state
/// nibble, temperatures) and its fault menu is Damiao's table.
#[test]
fn sim_damiao_serves_its_web_view() {
    use std::io::{Read, Write};

    let can = free_port();
    let ui = free_port();
    let mut sim = Sim(Command::new(ARMHIL)
        .args(["sim", "damiao", "--motor", "3:DM8009", "--socketcand"])
        .arg(format!("127.0.0.1:{can}"))
        .args(["--ui", &format!("127.0.0.1:{ui}")])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("armhil sim damiao starts"));
    let deadline = Instant::now() + Duration::from_secs(20);
    while !listens(("127.0.0.1", ui)) {
        assert!(Instant::now() < deadline, "the web view never listened");
        assert!(sim.0.try_wait().unwrap().is_none(), "the emulator exited");
        std::thread::sleep(Duration::from_millis(50));
    }
    let get = |path: &str| -> serde_json::Value {
        let mut stream = std::net::TcpStream::connect(("127.0.0.1", ui)).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(5)))
            .unwrap();
        write!(
            stream,
            "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{ui}\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut response = String::new();
        stream.read_to_string(&mut response).unwrap();
        let body = response.split_once("\r\n\r\n").expect("a response").1;
        serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {response}"))
    };
    let hello = get("/hello.json");
    assert_eq!(hello["device"], "damiao");
    assert_eq!(hello["motors"], serde_json::json!([3]));
    assert_eq!(hello["faults"][0]["name"], "over_voltage");
    let state = get("/state.json");
    let motor = &state["motors"][0];
    assert_eq!(
        (&motor["id"], &motor["mst_id"], &motor["model"]),
        (
            &serde_json::json!(3),
            &serde_json::json!(0x13),
            &serde_json::json!("DM8009")
        )
    );
    assert_eq!(
        (&motor["enabled"], &motor["mode"], &motor["state_name"]),
        (
            &serde_json::json!(false),
            &serde_json::json!("mit"),
            &serde_json::json!("disabled")
        )
    );
    assert_eq!(motor["rotor_temperature_c"], 25.0);
}
