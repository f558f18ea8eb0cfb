//! vcan end-to-end: our Piper driver against `armhil sim piper` (a separate process) over
//! SocketCAN, in real time. Timeouts are generous: under TCG emulation everything runs several
//! times slower.
#![cfg(target_os = "linux")]

use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::Duration;

use bus::socketcan_bus::SocketCanBus;
use bus::CanBus;
use driver::piper::{GripperCommand, MotorSelect, MoveKind, PiperBuilder, PiperError, Timeouts};

/// Kills the emulator process however the test ends.
struct ChildGuard(Child);

impl Drop for ChildGuard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn iface() -> String {
    std::env::var("ARMHIL_VCAN_IFACE").unwrap_or_else(|_| "vcan0".to_owned())
}

fn armhil_bin() -> String {
    std::env::var("ARMHIL_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_armhil").to_owned())
}

fn slow_vm_timeouts() -> Timeouts {
    Timeouts {
        first_feedback: Some(Duration::from_secs(60)),
        query: Duration::from_secs(5),
        enable: Duration::from_secs(20),
        enable_retry: Duration::from_millis(200),
        link: Duration::from_millis(500),
        send: Duration::from_secs(1),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs a live vcan interface: run scripts/vcan-e2e.sh"]
async fn piper_driver_flow_over_vcan() {
    let iface = iface();
    let child = Command::new(armhil_bin())
        .args(["sim", "piper", "--iface", &iface])
        .stdin(Stdio::null())
        .spawn()
        .expect("armhil sim piper starts");
    let _guard = ChildGuard(child);

    let bus: Arc<dyn CanBus> =
        Arc::new(SocketCanBus::open(&iface).expect("open the vcan interface"));
    let piper = PiperBuilder::new(bus)
        .timeouts(slow_vm_timeouts())
        .connect()
        .await
        .expect("connect");

    let info = piper.query_firmware().await.expect("firmware reply");
    assert!(info.software.starts_with("S-V"), "{info:?}");
    assert_eq!(piper.firmware_version(), info.version);

    piper
        .enable(MotorSelect::All)
        .await
        .expect("enable confirmed");
    let target = [0.2, 0.4, -0.4, 0.1, -0.2, 0.3];
    piper.move_joints_rad(target, 100).await.expect("move");
    piper
        .wait_for_move_mode(MoveKind::J, Duration::from_secs(5))
        .await
        .expect("MOVE J echoed");
    let state = piper
        .wait_for_arrival(0.02, Duration::from_secs(90))
        .await
        .expect("arrival");
    let joints = state.joints_rad().expect("joints");
    for i in 0..6 {
        assert!(
            (joints[i] - target[i]).abs() < 0.02,
            "{joints:?} vs {target:?}"
        );
    }

    let command = GripperCommand {
        stroke_m: 0.02,
        effort_nm: 1.0,
        enable: true,
        clear_error: false,
    };
    piper.gripper(command).await.expect("gripper");
    piper
        .wait_for(
            |s| {
                s.gripper_stroke_m()
                    .is_some_and(|m| (m - 0.02).abs() < 0.002)
            },
            Duration::from_secs(60),
            "gripper at 20 mm",
        )
        .await
        .expect("gripper arrives");

    let limits = piper.query_all_joint_limits().await.expect("limits");
    assert!(limits
        .iter()
        .enumerate()
        .all(|(i, l)| usize::from(l.joint) == i + 1 && l.max_speed_rad_s > 0.0));
    let end = piper.query_end_limits().await.expect("end limits");
    assert!(end.linear_m_s > 0.0);
    assert!(piper.is_ok());

    piper
        .disable(MotorSelect::All)
        .await
        .expect("disable confirmed");
    piper.disconnect().await;
    drop(_guard);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs a live vcan interface: run scripts/vcan-e2e.sh"]
async fn piper_driver_query_times_out_without_an_emulator() {
    let iface = iface();
    let timeouts = Timeouts {
        first_feedback: None,
        query: Duration::from_millis(500),
        ..slow_vm_timeouts()
    };
    // The builder's own SocketCAN opener this time.
    let piper = PiperBuilder::interface(&iface)
        .timeouts(timeouts)
        .connect()
        .await
        .expect("connect");
    let start = tokio::time::Instant::now();
    let result = piper.query_joint_limits(1).await;
    assert!(
        matches!(result, Err(PiperError::Timeout { .. })),
        "{result:?}"
    );
    assert!(start.elapsed() < Duration::from_secs(10));
    piper.disconnect().await;
}
