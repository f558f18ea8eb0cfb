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

/// A motor powered on in the MIT variant (its flash says protocol 2).
fn mit_actuator(model: SModel) -> sim::robstride::Actuator {
    let saved = sim::robstride::PersistedMotor {
        can_id: 0x7F,
        master_id: 0xFD,
        zero_offset_rad: 0.0,
        params: std::collections::BTreeMap::new(),
        baud_code: 1,
        protocol: 2,
    };
    sim::robstride::Actuator::new(MotorConfig::new(0x7F, model), Some(&saved), 1_000_000)
}

/// Command 14 on the emulator: the f32 at `index`.
fn read_f32(m: &mut sim::robstride::Actuator, index: u16) -> f32 {
    let [lo, hi] = index.to_le_bytes();
    let frame = bus::CanFrame::standard(0x37F, &[lo, hi, 0, 0, 0, 0, 0, 0]).unwrap();
    let replies = m.handle_frame(&frame);
    assert_eq!(replies.len(), 1, "{replies:?}");
    let d = replies[0].data();
    f32::from_le_bytes([d[4], d[5], d[6], d[7]])
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(128))]

    /// Driver encode → emulator decode: the MIT setpoint the emulator holds (cmdPos 0x3012,
    /// cmdVel 0x3013) is the driver's, within one step of its 16- or 12-bit field; the
    /// emulator's Response 1 decodes in the driver to the emulator's state within one step.
    #[test]
    fn mit_setpoints_and_status_agree_across_the_two_codecs(
        angle in -13.0f32..13.0, speed in -25.0f32..25.0, kp in 0.0f32..5000.0,
        kd in 0.0f32..100.0, torque in -60.0f32..60.0,
    ) {
        let ranges = DModel::RS03.ranges(driver::robstride::RangeTable::Manual);
        let cmd = OpControl { angle_rad: angle, speed_rad_s: speed, kp, kd, torque_nm: torque };
        let frame = driver::robstride::mit_codec::setpoint(0x7F, &cmd, &ranges).unwrap();
        let mut m = mit_actuator(SModel::RS03);
        let replies = m.handle_frame(&frame);
        proptest::prop_assert_eq!(replies.len(), 1);
        let p = ranges.angle_rad;
        let angle_step = 2.0 * p / 65535.0;
        let speed_step = 2.0 * ranges.speed_rad_s / 4095.0;
        let held_angle = read_f32(&mut m, 0x3012);
        let held_speed = read_f32(&mut m, 0x3013);
        proptest::prop_assert!((held_angle - angle.clamp(-p, p)).abs() <= angle_step * 1.01,
            "{held_angle} vs {angle}");
        let clamped = speed.clamp(-ranges.speed_rad_s, ranges.speed_rad_s);
        proptest::prop_assert!((held_speed - clamped).abs() <= speed_step * 1.01,
            "{held_speed} vs {speed}");
        let decoded = driver::robstride::mit_codec::decode(&replies[0], 0xFD, |_| Some(ranges));
        let Some(driver::robstride::MitIncoming::Status(status)) = decoded else {
            return Err(proptest::test_runner::TestCaseError::fail(format!("{decoded:?}")));
        };
        let snap = m.snapshot();
        proptest::prop_assert_eq!(status.motor_id, 0x7F);
        proptest::prop_assert!((f64::from(status.angle_rad) - snap.angle_rad).abs() <= 2e-4);
        proptest::prop_assert!((f64::from(status.temperature_c) - snap.temperature_c).abs() <= 0.051);
    }
}

#[test]
fn random_frames_never_panic_the_mit_front_end_and_get_at_most_one_reply() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(20);
    let mut m = mit_actuator(SModel::RS04);
    for i in 0..20_000 {
        let len = rng.random_range(0..=8);
        let mut data = [0u8; 8];
        rng.fill(&mut data[..]);
        // Mostly this motor's identifiers (kinds 0..7), sometimes any 11- or 29-bit one.
        let frame = match i % 10 {
            0 => bus::CanFrame::extended(rng.random_range(0..0x2000_0000), &data[..len]),
            1 => bus::CanFrame::standard(rng.random_range(0..0x800), &data[..len]),
            _ => bus::CanFrame::standard(rng.random_range(0..8u16) << 8 | 0x7F, &data[..len]),
        }
        .unwrap();
        let replies = m.handle_frame(&frame);
        assert!(replies.len() <= 1, "{frame}: {replies:?}");
        assert!(
            replies.iter().all(|r| !r.is_extended()),
            "{frame}: {replies:?}"
        );
        if i % 50 == 0 {
            m.tick();
        }
    }
    let snap = m.snapshot();
    assert!(snap.angle_rad.is_finite() && snap.speed_rad_s.is_finite());
    assert_eq!(
        snap.protocol, 2,
        "the protocol in force never changes without a power cycle"
    );
}
