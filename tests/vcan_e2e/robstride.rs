//! vcan end-to-end: `armhil sim robstride` with two motors as a child process, driven by our
//! driver over SocketCAN, and checked with can-utils' `candump -L`: every frame is an extended
//! frame laid out as spec §2 says (type in bits 28..24, host/motor IDs in bits 15..8 / 7..0).
//!
//! Real clock, multi-thread runtime; bounds are generous for a TCG-emulated VM.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use bus::socketcan_bus::SocketCanBus;
use bus::CanBus;
use driver::robstride::{
    DriverConfig, Model, MotorMode, OpControl, Param, RobstrideDriver, RunMode,
};

/// How long the emulator may take to come up, or a candump line to appear.
const WAIT: Duration = Duration::from_secs(30);

fn iface() -> String {
    std::env::var("ARMHIL_VCAN_IFACE").unwrap_or_else(|_| "vcan0".to_owned())
}

fn armhil_bin() -> PathBuf {
    std::env::var_os("ARMHIL_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_armhil")))
}

/// Kills its child on drop so a failing test leaves nothing on the bus.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `candump -L iface`, its lines delivered through a channel.
fn candump(iface: &str) -> (Killed, mpsc::Receiver<String>) {
    let mut child = Command::new("candump")
        .args(["-L", iface])
        .stdout(Stdio::piped())
        .spawn()
        .expect("candump (can-utils) runs");
    let stdout = child.stdout.take().expect("piped stdout");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    (Killed(child), rx)
}

/// Parse `(time) iface ID#DATA` into (ID text, ID, data).
fn parse_candump(line: &str) -> Option<(String, u32, Vec<u8>)> {
    let token = line.split_whitespace().nth(2)?;
    let (id, data) = token.split_once('#')?;
    let raw = u32::from_str_radix(id, 16).ok()?;
    let bytes = (0..data.len() / 2)
        .map(|i| u8::from_str_radix(&data[2 * i..2 * i + 2], 16).ok())
        .collect::<Option<Vec<u8>>>()?;
    Some((id.to_owned(), raw, bytes))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs a live vcan interface and can-utils (scripts/vcan-e2e.sh)"]
async fn armhil_sim_robstride_answers_our_driver_with_spec_layout_frames() {
    let iface = iface();
    let (_candump, lines) = candump(&iface);
    // Give candump a moment to bind before traffic starts.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let _emulator = Killed(
        Command::new(armhil_bin())
            .args([
                "sim",
                "robstride",
                "--iface",
                &iface,
                "--motor",
                "1:RS03",
                "--motor",
                "2:RS00",
            ])
            .stdin(Stdio::null())
            .spawn()
            .expect("armhil runs"),
    );
    let socket: Arc<dyn CanBus> = Arc::new(SocketCanBus::open(&iface).expect("open vcan"));
    let config = DriverConfig {
        timeout: Duration::from_secs(2),
        ..DriverConfig::default()
    };
    let driver = RobstrideDriver::new(socket, config);
    let arm = driver.motor(1, Model::RS03).expect("handle 1");
    let disc = driver.motor(2, Model::RS00).expect("handle 2");

    // Wait for the emulator to come up.
    let deadline = tokio::time::Instant::now() + WAIT;
    let uid1 = loop {
        match arm.device_id().await {
            Ok(uid) => break uid,
            Err(error) if tokio::time::Instant::now() > deadline => {
                panic!("emulator never answered: {error}")
            }
            Err(_) => tokio::time::sleep(Duration::from_millis(200)).await,
        }
    };
    let uid2 = disc.device_id().await.expect("motor 2 answers");
    assert_ne!(uid1, uid2);

    assert_eq!(arm.enable().await.expect("enable").mode, MotorMode::Run);
    let cmd = OpControl {
        angle_rad: 0.5,
        speed_rad_s: 0.0,
        kp: 50.0,
        kd: 2.0,
        torque_nm: 0.0,
    };
    for _ in 0..20 {
        assert_eq!(arm.op_control(cmd).await.expect("op control").motor_id, 1);
    }
    disc.switch_mode(RunMode::Velocity)
        .await
        .expect("velocity mode");
    disc.set_velocity(3.0, 5.0, 20.0).await.expect("velocity");
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let speed = disc.read_f32(Param::MechVel).await.expect("mechVel");
    assert!((speed - 3.0).abs() < 0.3, "disc at {speed} rad/s");
    let version = arm.firmware_version().await.expect("version");
    assert_eq!(version, [0, 3, 1, 41]);
    disc.disable(true).await.expect("stop");

    // candump saw every frame as an extended frame with the §2 layout.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let mut frames = Vec::new();
    while let Ok(line) = lines.recv_timeout(Duration::from_millis(200)) {
        frames.push(line);
    }
    assert!(
        frames.len() >= 40,
        "candump saw only {} frames",
        frames.len()
    );
    let mut from_motors = 0;
    for line in &frames {
        let (id_text, id, data) = parse_candump(line).unwrap_or_else(|| panic!("bad line {line}"));
        assert_eq!(id_text.len(), 8, "not an extended frame: {line}");
        assert!(id <= 0x1FFF_FFFF && data.len() == 8, "{line}");
        let comm_type = (id >> 24) & 0x1F;
        let (mid, low) = ((id >> 8) & 0xFF, id & 0xFF);
        match comm_type {
            // Motor → host: motor ID in 15..8, host in 7..0. (17 also goes host → motor.)
            2 | 17 | 21 | 24 if low == 0xFD => {
                assert!(mid == 1 || mid == 2, "{line}");
                from_motors += 1;
            }
            // Type 0 replies: motor ID in 15..8, 0xFE in 7..0.
            0 if low == 0xFE => {
                assert!(mid == 1 || mid == 2, "{line}");
                from_motors += 1;
            }
            // Type 1 carries the torque in 23..8, no host ID.
            1 => assert!(low == 1 || low == 2, "{line}"),
            // Host → motor: host in 15..8, motor in 7..0.
            0 | 3 | 4 | 6 | 7 | 17 | 18 | 22 | 23 | 25 => {
                assert_eq!(mid, 0xFD, "{line}");
                assert!(low == 1 || low == 2, "{line}");
            }
            other => panic!("unexpected comm type {other}: {line}"),
        }
    }
    assert!(from_motors >= 20, "{from_motors} motor frames");
}
