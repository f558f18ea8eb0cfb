use driver::damiao::{ControlMode, DamiaoError, MotorError, MotorState};

use super::actions::classify;
use super::*;
use crate::scenario::ErrorClass;

#[test]
fn driver_errors_get_the_scenario_error_classes() {
    let feedback = driver::damiao::Feedback {
        motor: 1,
        state: MotorState::CommunicationLost,
        position_rad: 0.0,
        velocity_rad_s: 0.0,
        torque_nm: 0.0,
        mos_temp_c: 25,
        rotor_temp_c: 25,
    };
    let cases = [
        (
            DamiaoError::Timeout {
                motor: 1,
                bus: "vcan0".into(),
                request: "refresh",
                after: Duration::from_millis(20),
            },
            ErrorClass::Timeout,
        ),
        (
            DamiaoError::Motor(MotorError {
                motor: 1,
                bus: "vcan0".into(),
                state: MotorState::CommunicationLost,
                feedback,
            }),
            ErrorClass::Rejected,
        ),
        (
            DamiaoError::WrongMode {
                motor: 1,
                bus: "vcan0".into(),
                mode: ControlMode::Mit,
                command: ControlMode::Velocity,
            },
            ErrorClass::InvalidArgument,
        ),
        (
            DamiaoError::OutOfRange {
                field: "kp",
                value: 600.0,
                min: 0.0,
                max: 500.0,
            },
            ErrorClass::InvalidArgument,
        ),
        (DamiaoError::Closed, ErrorClass::Bus),
    ];
    for (error, class) in cases {
        assert_eq!(classify(&error), class, "{error}");
    }
}

#[tokio::test(start_paused = true)]
async fn a_nan_motor_state_is_an_emulator_error() {
    let bus = VirtualBus::new(bus::virtual_bus::VirtualBusConfig::default());
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    let config = DamiaoConfig::new(vec![sim::damiao::MotorConfig::new(
        4,
        sim::damiao::Model::DM4310,
    )]);
    let handle = DamiaoBus::spawn(config, node).unwrap();
    let mut motors = handle.snapshot().await.unwrap();
    handle.shutdown().await;
    assert_eq!(dm_health(&motors), Ok(()));
    motors[0].torque_nm = f64::NAN;
    let err = dm_health(&motors).unwrap_err();
    assert!(err.contains("motor 4 torque is NaN"), "{err}");
}

/// The host reads every motor on its own (a Damiao motor sends nothing unasked); `poll`
/// stops one motor's reads, and a power cycle gives fresh handles that read again.
#[tokio::test(start_paused = true)]
async fn the_host_reads_each_motor_until_told_to_stop() {
    let bus = VirtualBus::new(bus::virtual_bus::VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let settings = DamiaoSettings {
        bus: None,
        motors: vec![
            sim::damiao::MotorConfig::new(1, sim::damiao::Model::DM4310),
            sim::damiao::MotorConfig::new(2, sim::damiao::Model::DM8009),
        ],
    };
    let device = DamiaoDevice::start("dm", &settings, host, Some(&bus), Duration::from_millis(20))
        .expect("starts");
    tokio::time::sleep(Duration::from_millis(25)).await;
    let obs = device.observe();
    assert_eq!(obs[&1].state, Some("disabled"));
    assert_eq!(obs[&2].rotor_temp_c, Some(25.0));
    device.set_poll(2, Duration::ZERO);
    let stopped = lock(&device.polls)[&2].task.is_none();
    assert!(stopped);
    let action =
        |command| Action::Damiao(crate::devices::damiao::model::DamiaoAction { motor: 0, command });
    device
        .perform(
            &action(crate::devices::damiao::model::DmCommand::Restart),
            None,
        )
        .await
        .expect("restarts");
    // Motor 1 is read again; motor 2's reads stay off across the power cycle.
    assert!(lock(&device.polls)[&1].task.is_some());
    assert!(lock(&device.polls)[&2].task.is_none());
    tokio::time::sleep(Duration::from_millis(25)).await;
    assert_eq!(device.observe()[&1].state, Some("disabled"));
    assert_eq!(device.observe()[&2].state, None);
    device.shutdown().await;
}
