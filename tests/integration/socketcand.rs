//! The emulators served over socketcand by the `armhil` binary, reached by our drivers through
//! the socketcand client: `armhil sim … --socketcand` and `armhil run --socketcand`.

use std::process::Command;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bus::socketcand::SocketcandBus;
use bus::CanBus;
use driver::robstride::{DriverConfig, Model, RobstrideDriver, RunMode};

use super::support::{start_sim, ARMHIL};

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
