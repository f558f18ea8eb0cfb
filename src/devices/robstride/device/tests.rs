use driver::robstride::{
    FaultReport, Feedback, FeedbackKind, MotorMode, RobstrideError, StatusFaults,
};

use super::actions::classify;
use super::*;
use crate::devices::robstride::model::MotorCond;
use crate::devices::robstride::observe::{observe_motor, Observation};
use crate::scenario::{ErrorClass, Near};

fn feedback(faults: u8, mode: MotorMode) -> Feedback {
    Feedback {
        motor_id: 3,
        mode,
        faults: StatusFaults(faults),
        angle_rad: 1.5,
        speed_rad_s: -2.0,
        torque_nm: 0.75,
        temperature_c: 41.0,
        kind: FeedbackKind::ActiveReport,
        timestamp: Duration::ZERO,
    }
}

#[test]
fn status_bits_and_fault_words_map_to_names_in_bit_order() {
    let report = FaultReport {
        fault_word: (1 << 16) | (1 << 5) | (1 << 3),
        warning_word: 1,
    };
    let m = observe_motor(Some(feedback(0x14, MotorMode::Reset)), Some(report));
    assert_eq!(m.status_faults, vec!["over_temperature", "stall_overload"]);
    assert_eq!(
        m.fault_report,
        vec![
            "over_voltage",
            "phase_a_over_current",
            "phase_c_over_current",
            "over_temperature_warning"
        ]
    );
    assert_eq!(m.mode_state, Some("reset"));
    assert_eq!(m.feedback, Some("active_report"));
    assert_eq!(m.angle_rad, Some(1.5));
}

#[test]
fn motor_conditions_judge_the_right_motor() {
    let mut obs = Observation::default();
    obs.insert(3, observe_motor(Some(feedback(0, MotorMode::Run)), None));
    let near = |value, tolerance| Near { value, tolerance };
    assert!(MotorCond::Velocity(near(-2.0, 0.1)).holds(3, &obs));
    assert!(!MotorCond::Velocity(near(2.0, 0.1)).holds(3, &obs));
    assert!(!MotorCond::Velocity(near(-2.0, 0.1)).holds(4, &obs));
    assert!(MotorCond::Torque(near(0.7, 0.1)).holds(3, &obs));
    assert!(MotorCond::TempMin(40.0).holds(3, &obs));
    assert!(!MotorCond::TempMax(40.0).holds(3, &obs));
    assert!(MotorCond::ModeState("run").holds(3, &obs));
    assert!(MotorCond::StatusFaults(vec![]).holds(3, &obs));
    assert!(MotorCond::FaultReport(vec![]).holds(3, &obs));
    assert!(!MotorCond::StatusFaults(vec!["under_voltage"]).holds(3, &obs));
    assert_eq!(
        MotorCond::Position(near(1.0, 0.05)).actual_text(3, &obs),
        "motor 3 position_rad 1.50"
    );
    assert_eq!(
        MotorCond::Position(near(1.0, 0.05)).actual_text(9, &obs),
        "motor 9 not on the bus"
    );
}

#[test]
fn driver_errors_get_the_scenario_error_classes() {
    assert_eq!(
        classify(&RobstrideError::ParamRefused {
            motor: 1,
            index: 0x7019
        }),
        ErrorClass::Rejected
    );
    assert_eq!(
        classify(&RobstrideError::Timeout {
            motor: 1,
            request: "poll",
            after: Duration::from_millis(20)
        }),
        ErrorClass::Timeout
    );
    assert_eq!(
        classify(&RobstrideError::InvalidCanId { id: 0 }),
        ErrorClass::InvalidArgument
    );
    assert_eq!(
        classify(&RobstrideError::MitEnableRefused {
            motor: 1,
            fault: true
        }),
        ErrorClass::Rejected
    );
}

#[tokio::test(start_paused = true)]
async fn a_nan_motor_state_is_an_emulator_error() {
    let bus = VirtualBus::new(bus::virtual_bus::VirtualBusConfig::default());
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    let config = RobstrideConfig::new(vec![sim::robstride::MotorConfig::new(
        4,
        sim::robstride::Model::RS00,
    )]);
    let handle = RobstrideBus::spawn(node, config).unwrap();
    let mut motors = handle.snapshot().await.unwrap();
    handle.shutdown().await;
    assert_eq!(rs_health(&motors), Ok(()));
    motors[0].speed_rad_s = f64::INFINITY;
    let err = rs_health(&motors).unwrap_err();
    assert!(err.contains("motor 4 speed is inf"), "{err}");
}
