//! The RobStride driver's MIT client against the emulator on the virtual bus (paused clock):
//! the private switch (type 25 F_CMD 2), a power cycle, the three MIT mode sequences, faults,
//! parameters (including the host-tool tables), and command 8 back to the private protocol.
//! Also the host-tool reads the official Python SDK makes (0x3016/0x3017/0x302C/0x2005)
//! through the private driver.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::CanBus;
use driver::robstride::{
    DriverConfig, MitMode, Model as DModel, MotorMode, OpControl, Param, ParamType, ParamValue,
    Protocol, RobstrideDriver, RobstrideError,
};
use sim::robstride::{
    Fault, Load, Model as SModel, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideHandle,
};

fn config(state: &std::path::Path) -> RobstrideConfig {
    let mut config = RobstrideConfig::new(vec![
        MotorConfig::new(1, SModel::RS03).with_load(Load::Pendulum {
            mass_kg: 1.0,
            length_m: 0.3,
        }),
        MotorConfig::new(2, SModel::RS00),
    ]);
    config.state_file = Some(state.to_path_buf());
    config
}

fn power_on(bus: &VirtualBus, config: RobstrideConfig) -> RobstrideHandle {
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("robstride-emulator"));
    RobstrideBus::spawn(node, config).expect("emulator starts")
}

#[tokio::test(start_paused = true)]
async fn switch_to_mit_drive_all_modes_and_switch_back() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("state.json");
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let private = driver.motor(1, DModel::RS03).unwrap();
    let mit = driver.mit_motor(1, DModel::RS03).unwrap();

    // Private protocol: switch to MIT (after the next power cycle).
    let emulator = power_on(&bus, config(&state));
    let uid = private.set_protocol(Protocol::Mit).await.unwrap();
    private
        .enable()
        .await
        .expect("still private until power-off");
    assert!(matches!(
        mit.enable().await,
        Err(RobstrideError::Timeout { .. })
    ));
    emulator.shutdown().await;

    // Power cycle: MIT only; motor 2 (not switched) stays private.
    let emulator = power_on(&bus, config(&state));
    assert!(matches!(
        private.enable().await,
        Err(RobstrideError::Timeout { .. })
    ));
    let other = driver.motor(2, DModel::RS00).unwrap();
    other.enable().await.expect("motor 2 is still private");

    // MIT mode: hold the pendulum at 1 rad.
    let status = mit.enable().await.unwrap();
    assert_eq!((status.mode, status.fault), (MotorMode::Run, false));
    let setpoint = OpControl {
        angle_rad: 1.0,
        speed_rad_s: 0.0,
        kp: 200.0,
        kd: 5.0,
        torque_nm: 0.0,
    };
    for _ in 0..200 {
        mit.control(setpoint).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let held = mit.control(setpoint).await.unwrap();
    // Steady state: kp·error = m·g·l·sin θ → error ≈ 2.48/200 rad.
    assert!((held.angle_rad - 1.0).abs() < 0.03, "{held:?}");
    assert!(held.torque_nm > 1.5 && held.torque_nm < 3.0, "{held:?}");
    let out_of_range = OpControl {
        kp: 6000.0,
        ..setpoint
    };
    assert!(matches!(
        mit.control(out_of_range).await,
        Err(RobstrideError::OutOfRange { field: "kp", .. })
    ));

    // Position mode (CSP semantics): stop, mode 1, enable, command 10.
    mit.stop().await.unwrap();
    mit.set_mode(MitMode::Position).await.unwrap();
    mit.enable().await.unwrap();
    mit.set_position(-0.5, 3.0).await.unwrap();
    tokio::time::sleep(Duration::from_secs(2)).await;
    let at = mit.read_param(Param::MechPos).await.unwrap().as_f64();
    assert!((at + 0.5).abs() < 0.02, "mechPos {at}");
    // The host table reads the same angle (0x3016 mechPos on RS03).
    let table = mit.read_raw(0x3016, ParamType::F32).await.unwrap().as_f64();
    assert!((table - at).abs() < 0.01, "{table} vs {at}");
    // A mode change while running is ignored; the read-back catches it.
    assert!(matches!(
        mit.set_mode(MitMode::Velocity).await,
        Err(RobstrideError::ModeNotApplied {
            wanted: 2,
            actual: 5,
            ..
        })
    ));

    // Velocity mode: stop, mode 2, enable, command 11.
    mit.stop().await.unwrap();
    mit.set_mode(MitMode::Velocity).await.unwrap();
    mit.enable().await.unwrap();
    mit.set_velocity(2.0, 20.0).await.unwrap();
    tokio::time::sleep(Duration::from_secs(1)).await;
    let spinning = mit.set_velocity(2.0, 20.0).await.unwrap();
    // The pendulum's weight slows and speeds the turn by a few percent (speed loop, 20 A).
    assert!((spinning.speed_rad_s - 2.0).abs() < 0.15, "{spinning:?}");
    mit.stop().await.unwrap();

    // Parameters: a write returns the stored (clamped) value; unknown indices have no reply.
    let stored = mit
        .write_param(Param::LimitSpd, ParamValue::F32(99.0))
        .await
        .unwrap();
    assert_eq!(stored, ParamValue::F32(20.0));
    assert!(matches!(
        mit.read_raw(0x7007, ParamType::F32).await,
        Err(RobstrideError::ParamReadFailed { index: 0x7007, .. })
    ));
    assert!(matches!(
        mit.write_param(Param::MechPos, ParamValue::F32(1.0)).await,
        Err(RobstrideError::ParamRefused { .. })
    ));

    // Faults: no type 21 in MIT; the fault query and Response 1 show them.
    emulator.inject(1, Fault::OverVoltage).await.unwrap();
    assert_eq!(mit.fault_word().await.unwrap(), 1 << 3);
    assert!(matches!(
        mit.enable().await,
        Err(RobstrideError::MitEnableRefused { fault: true, .. })
    ));
    emulator.clear(1, Fault::OverVoltage).await.unwrap();
    assert!(!mit.clear_faults().await.unwrap().fault);
    assert_eq!(mit.fault_word().await.unwrap(), 0);

    // Command 8 back to private: the UID answers now, private after the power cycle.
    assert_eq!(mit.switch_protocol(Protocol::Private).await.unwrap(), uid);
    emulator.shutdown().await;
    let emulator = power_on(&bus, config(&state));
    assert!(matches!(
        mit.stop().await,
        Err(RobstrideError::Timeout { .. })
    ));
    private.enable().await.expect("private again");
    private.disable(false).await.unwrap();
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!((snapshot[0].protocol, snapshot[0].listening), (0, true));
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn the_sdk_host_table_reads_answer_live_values() {
    let dir = tempfile::tempdir().unwrap();
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = power_on(&bus, config(&dir.path().join("state.json")));
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let driver = RobstrideDriver::new(host, DriverConfig::default());
    let arm = driver.motor(1, DModel::RS03).unwrap();
    arm.switch_mode(driver::robstride::RunMode::Velocity)
        .await
        .unwrap();
    arm.set_velocity(1.5, 20.0, 20.0).await.unwrap();
    tokio::time::sleep(Duration::from_millis(800)).await;
    // What the official SDK reads (index, f32) and what it gets: status ok and live values.
    let pos = arm.read_raw(0x3016, ParamType::F32).await.unwrap().as_f64();
    let vel = arm.read_raw(0x3017, ParamType::F32).await.unwrap().as_f64();
    let torque = arm.read_raw(0x302C, ParamType::F32).await.unwrap().as_f64();
    let by_70xx = arm.read_f32(Param::MechPos).await.unwrap();
    assert!(
        (pos - f64::from(by_70xx)).abs() < 0.01,
        "{pos} vs {by_70xx}"
    );
    // The pendulum's weight modulates the speed by a few percent around 1.5 rad/s.
    assert!((vel - 1.5).abs() < 0.1, "mechVel {vel}");
    assert!(
        torque.abs() > 0.1,
        "torque_fdb {torque}: gravity on the pendulum"
    );
    let offset = arm.read_raw(0x2005, ParamType::F32).await.unwrap().as_f64();
    assert_eq!(offset, 0.0);
    // The strings still fail, as on hardware.
    assert!(matches!(
        arm.read_raw(0x1003, ParamType::U32).await,
        Err(RobstrideError::ParamReadFailed { index: 0x1003, .. })
    ));
    emulator.shutdown().await;
}
