//! The RobStride driver against the RobStride emulator on the virtual bus (paused clock):
//! two motors, interleaved traffic, run modes, faults, the watchdog and a power cycle.

use std::f32::consts::FRAC_PI_2;
use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::CanBus;
use driver::robstride::{
    DriverConfig, FeedbackKind, Model as DModel, MotorMode, OpControl, Param, RobstrideDriver,
    RobstrideError, RunMode,
};
use sim::robstride::{
    Fault, Load, Model as SModel, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle,
};

const G: f64 = 9.80665;

fn two_motor_config() -> RobstrideConfig {
    RobstrideConfig::new(vec![
        MotorConfig::new(1, SModel::RS03).with_load(Load::Pendulum {
            mass_kg: 1.0,
            length_m: 0.3,
        }),
        MotorConfig::new(2, SModel::RS00).with_load(Load::Disc {
            mass_kg: 1.0,
            radius_m: 0.1,
        }),
    ])
}

fn start(bus: &VirtualBus, config: RobstrideConfig) -> (RobstrideHandle, RobstrideDriver) {
    let emulator_node: Arc<dyn CanBus> = Arc::new(bus.attach("robstride-emulator"));
    let handle = RobstrideBus::spawn(emulator_node, config).expect("emulator starts");
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    (handle, RobstrideDriver::new(host, DriverConfig::default()))
}

#[tokio::test(start_paused = true)]
async fn two_motors_with_interleaved_traffic_each_get_their_own_replies() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let (emulator, driver) = start(&bus, two_motor_config());
    let arm = driver.motor(1, DModel::RS03).unwrap();
    let disc = driver.motor(2, DModel::RS00).unwrap();
    assert_ne!(
        arm.device_id().await.unwrap(),
        disc.device_id().await.unwrap()
    );

    arm.switch_mode(RunMode::CyclicPosition).await.unwrap();
    disc.switch_mode(RunMode::Velocity).await.unwrap();
    arm.set_position(FRAC_PI_2, 2.0).await.unwrap();
    disc.set_velocity(5.0, 10.0, 10.0).await.unwrap();

    // Poll both concurrently for 5 s: every reply must come from the motor asked.
    for _ in 0..500 {
        let (a, b) = tokio::join!(arm.poll(), disc.poll());
        assert_eq!(a.unwrap().motor_id, 1);
        assert_eq!(b.unwrap().motor_id, 2);
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let held = arm.poll().await.unwrap();
    assert!((held.angle_rad - FRAC_PI_2).abs() < 0.02, "{held:?}");
    let mgl = (1.0 * G * 0.3) as f32;
    assert!(
        (held.torque_nm - mgl).abs() <= 0.05 * mgl,
        "torque {} vs mgl {mgl}",
        held.torque_nm
    );
    let spinning = disc.poll().await.unwrap();
    assert!((spinning.speed_rad_s - 5.0).abs() < 0.1, "{spinning:?}");
    let by_param = disc.read_f32(Param::MechVel).await.unwrap();
    assert!((by_param - 5.0).abs() < 0.1);

    // Operation control on the disc while the arm keeps holding.
    disc.switch_mode(RunMode::OperationControl).await.unwrap();
    let cmd = OpControl {
        angle_rad: 1.0,
        speed_rad_s: 0.0,
        kp: 20.0,
        kd: 1.0,
        torque_nm: 0.0,
    };
    for _ in 0..300 {
        let (a, b) = tokio::join!(disc.op_control(cmd), arm.poll());
        assert_eq!(a.unwrap().motor_id, 2);
        assert_eq!(b.unwrap().motor_id, 1);
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let at = disc.poll().await.unwrap();
    assert!((at.angle_rad - 1.0).abs() < 0.02, "{at:?}");
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!(snapshot[0].run_mode, 5);
    assert_eq!(snapshot[1].run_mode, 0);
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn mode_switch_refused_while_running_is_detected_and_pp_current_zero_work() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let (emulator, driver) = start(&bus, two_motor_config());
    let disc = driver.motor(2, DModel::RS00).unwrap();
    disc.enable().await.unwrap();
    // Writing run_mode while enabled is ignored by the firmware; the read-back shows it.
    disc.write_param(Param::RunMode, 2.0).await.unwrap();
    let mode = disc.read_param(Param::RunMode).await.unwrap();
    assert_eq!(mode.as_f64(), 0.0);

    disc.switch_mode(RunMode::ProfilePosition).await.unwrap();
    disc.move_profile(3.0, 2.0, 5.0).await.unwrap();
    tokio::time::sleep(Duration::from_secs(3)).await;
    let fb = disc.poll().await.unwrap();
    assert!((fb.angle_rad - 3.0).abs() < 0.02, "{fb:?}");

    disc.switch_mode(RunMode::ZeroReturn).await.unwrap();
    tokio::time::sleep(Duration::from_secs(5)).await;
    assert!(disc.poll().await.unwrap().angle_rad.abs() < 0.02);

    disc.switch_mode(RunMode::Current).await.unwrap();
    disc.set_current(1.0).await.unwrap();
    tokio::time::sleep(Duration::from_millis(50)).await;
    let fb = disc.poll().await.unwrap();
    assert!((fb.torque_nm - 1.48).abs() < 0.02, "{fb:?}");
    let iqf = disc.read_f32(Param::Iqf).await.unwrap();
    assert!((iqf - 1.0).abs() < 1e-3);

    // Zeroing follows the manual's sequence and reads back zero.
    disc.switch_mode(RunMode::CyclicPosition).await.unwrap();
    disc.set_position(2.0, 3.0).await.unwrap();
    tokio::time::sleep(Duration::from_secs(2)).await;
    disc.zero_here().await.unwrap();
    assert!(disc.read_initial_position().await.unwrap().abs() < 0.01);
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn faults_reach_the_driver_and_clear_with_stop_and_clear() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let (emulator, driver) = start(&bus, two_motor_config());
    let arm = driver.motor(1, DModel::RS03).unwrap();
    let disc = driver.motor(2, DModel::RS00).unwrap();
    arm.enable().await.unwrap();
    emulator.inject(1, Fault::UnderVoltage).await.unwrap();
    tokio::time::sleep(Duration::from_millis(5)).await;
    let report = arm.last_fault_report().expect("type 21 arrived");
    assert!(report.under_voltage());
    assert!(
        disc.last_fault_report().is_none(),
        "the other motor saw nothing"
    );
    let fb = arm.poll().await.unwrap();
    assert_eq!(fb.mode, MotorMode::Reset);
    assert!(fb.faults.under_voltage());
    assert!(matches!(
        arm.enable().await,
        Err(RobstrideError::EnableRefused { motor: 1, .. })
    ));
    // Cause still present: clear does not help.
    arm.disable(true).await.unwrap();
    assert!(arm.enable().await.is_err());
    emulator.clear(1, Fault::UnderVoltage).await.unwrap();
    arm.disable(true).await.unwrap();
    assert_eq!(arm.enable().await.unwrap().mode, MotorMode::Run);
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn watchdog_and_active_reporting() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let (emulator, driver) = start(&bus, two_motor_config());
    let disc = driver.motor(2, DModel::RS00).unwrap();
    disc.set_can_timeout(Duration::from_millis(200))
        .await
        .unwrap();
    disc.enable().await.unwrap();
    tokio::time::sleep(Duration::from_millis(150)).await;
    assert_eq!(disc.poll().await.unwrap().mode, MotorMode::Run);
    tokio::time::sleep(Duration::from_millis(250)).await;
    assert_eq!(
        emulator.snapshot().await.unwrap()[1].mode,
        sim::robstride::ModeState::Reset
    );

    disc.set_report_period(Duration::from_millis(20))
        .await
        .unwrap();
    let mut reports = disc.subscribe_feedback();
    disc.set_active_reporting(true).await.unwrap();
    let start = tokio::time::Instant::now();
    let mut stamps = Vec::new();
    while stamps.len() < 10 && start.elapsed() < Duration::from_secs(1) {
        if tokio::time::timeout(Duration::from_millis(50), reports.changed())
            .await
            .is_ok()
        {
            if let Some(fb) = *reports.borrow_and_update() {
                if fb.kind == FeedbackKind::ActiveReport {
                    stamps.push(fb.timestamp);
                }
            }
        }
    }
    assert_eq!(stamps.len(), 10, "{stamps:?}");
    for pair in stamps.windows(2) {
        let gap = pair[1] - pair[0];
        assert!(
            gap >= Duration::from_micros(19_500) && gap <= Duration::from_micros(20_500),
            "{gap:?}"
        );
    }
    disc.set_active_reporting(false).await.unwrap();
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn saved_state_and_new_can_id_survive_a_power_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("state.json");
    let mut config = two_motor_config();
    config.state_file = Some(state.clone());

    let bus = VirtualBus::new(VirtualBusConfig::default());
    let (emulator, driver) = start(&bus, config.clone());
    let mut disc = driver.motor(2, DModel::RS00).unwrap();
    let uid = disc.device_id().await.unwrap();
    disc.set_can_id(9).await.unwrap();
    disc.write_param(Param::LimitSpd, 3.5).await.unwrap();
    disc.write_param(Param::LocKp, 12.0).await.unwrap();
    disc.save().await.unwrap();
    disc.write_param(Param::LocKp, 99.0).await.unwrap(); // not saved
    emulator.shutdown().await;
    drop(disc);
    drop(driver);

    let bus = VirtualBus::new(VirtualBusConfig::default());
    let (emulator, driver) = start(&bus, config);
    let old = driver.motor(2, DModel::RS00).unwrap();
    assert!(matches!(
        old.device_id().await,
        Err(RobstrideError::Timeout { .. })
    ));
    let disc = driver.motor(9, DModel::RS00).unwrap();
    assert_eq!(disc.device_id().await.unwrap(), uid);
    assert_eq!(disc.read_f32(Param::LimitSpd).await.unwrap(), 3.5);
    assert_eq!(disc.read_f32(Param::LocKp).await.unwrap(), 12.0);
    emulator.shutdown().await;
}
