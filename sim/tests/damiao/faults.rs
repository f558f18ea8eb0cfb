//! Errors: the CAN timeout latches D and FB clears it; each injected error shows in the
//! state nibble, stops the torque, refuses enable, and stays latched until its cause is gone
//! and the host sends FB.

use sim::actuator::ActuatorFirmware;
use sim::damiao::codec::{MitCommand, Special};
use sim::damiao::registers::rid;
use sim::damiao::{DamiaoMotor, Fault, Model};
use sim::fault_args::{FaultArgValue, FaultArgs};

use super::{mit, motor, one, refresh, run, special, write};

/// An enabled DM4310 holding position 0 under MIT against a 1 N·m push.
fn holding() -> DamiaoMotor {
    let mut m = motor(0x01, Model::DM4310);
    special(&mut m, Special::Enable);
    one(mit(
        &mut m,
        MitCommand {
            kp_nm_per_rad: 50.0,
            kd_nm_s_per_rad: 1.0,
            ..MitCommand::default()
        },
    ));
    m.set_external_torque(1.0);
    run(&mut m, 500);
    assert!((m.torque_nm() + 1.0).abs() < 0.05, "{}", m.torque_nm());
    m
}

#[test]
fn the_can_timeout_latches_d_and_fb_clears_it() {
    let mut m = holding();
    // TIMEOUT 2000 × 50 µs = 100 ms.
    one(write(&mut m, rid::TIMEOUT, 2000u32.to_le_bytes()));
    // Frames every 50 ms keep it alive.
    for _ in 0..6 {
        run(&mut m, 50);
        assert_eq!(refresh(&mut m).state, 1);
    }
    // Silence: enabled at 99 ms, latched at 100 ms.
    run(&mut m, 99);
    assert!(m.is_enabled());
    run(&mut m, 1);
    assert!(!m.is_enabled());
    assert_eq!(m.torque_nm(), 0.0);
    assert_eq!(refresh(&mut m).state, 0xD);
    assert_eq!(m.snapshot().faults, ["comm_lost"]);
    // Enable is refused while latched: the reply shows the error.
    assert_eq!(special(&mut m, Special::Enable).state, 0xD);
    // FB clears it (nothing keeps a timeout present); enable works again.
    assert_eq!(special(&mut m, Special::ClearError).state, 0);
    assert_eq!(special(&mut m, Special::Enable).state, 1);
}

#[test]
fn the_timeout_is_off_at_zero_and_ignores_a_disabled_motor() {
    let mut m = holding();
    run(&mut m, 3000);
    assert!(m.is_enabled(), "TIMEOUT 0 is off");
    one(write(&mut m, rid::TIMEOUT, 20u32.to_le_bytes()));
    special(&mut m, Special::Disable);
    run(&mut m, 100);
    assert_eq!(refresh(&mut m).state, 0);
}

#[test]
fn each_injected_error_shows_in_the_state_nibble_and_stops_the_torque() {
    for fault in Fault::ALL {
        let mut m = holding();
        let name = fault.name();
        let sent = m.inject(name, &FaultArgs::new()).unwrap();
        assert!(
            sent.is_empty(),
            "{name}: a Damiao motor reports only when asked"
        );
        assert!(!m.is_enabled(), "{name}");
        assert_eq!(refresh(&mut m).state, fault.code(), "{name}");
        run(&mut m, 50);
        assert_eq!(m.torque_nm(), 0.0, "{name}");
        assert!(
            m.speed_rad_s() > 0.1,
            "{name}: the push now turns the shaft"
        );
        assert_eq!(m.snapshot().faults, [name]);
        assert_eq!(
            special(&mut m, Special::Enable).state,
            fault.code(),
            "{name}"
        );
        // FB while the cause is present keeps the latch (comm_lost has no lasting cause).
        let after_fb = special(&mut m, Special::ClearError).state;
        if fault == Fault::CommLost {
            assert_eq!(after_fb, 0, "{name}");
        } else {
            assert_eq!(after_fb, fault.code(), "{name}: cause still present");
            // Clearing the cause leaves the latch until the host's FB.
            m.clear(name, &FaultArgs::new()).unwrap();
            run(&mut m, 10);
            assert_eq!(refresh(&mut m).state, fault.code(), "{name}");
            assert_eq!(special(&mut m, Special::ClearError).state, 0, "{name}");
        }
        assert_eq!(special(&mut m, Special::Enable).state, 1, "{name}");
        assert!(m.snapshot().faults.is_empty());
    }
}

#[test]
fn several_latched_errors_show_the_lowest_code() {
    let mut m = holding();
    m.inject("overload", &FaultArgs::new()).unwrap();
    m.inject("under_voltage", &FaultArgs::new()).unwrap();
    assert_eq!(refresh(&mut m).state, 0x9);
    m.clear("under_voltage", &FaultArgs::new()).unwrap();
    assert_eq!(special(&mut m, Special::ClearError).state, 0xE);
    assert_eq!(m.snapshot().faults, ["overload"]);
}

#[test]
fn injected_values_set_the_cause_and_bad_ones_are_refused() {
    let mut m = holding();
    let hot = FaultArgs::new().with("temperature_c", FaultArgValue::Number(150.0));
    m.inject("coil_over_temperature", &hot).unwrap();
    assert_eq!(m.coil_temperature_c(), 150.0);
    let fb = refresh(&mut m);
    assert_eq!((fb.state, fb.rotor_temp_c), (0xC, 150));
    // A value that would not trip, an argument a fault does not take, an unknown fault:
    // refused, nothing changes.
    let mut calm = holding();
    let mild = FaultArgs::new().with("voltage_v", FaultArgValue::Number(30.0));
    let error = calm.inject("under_voltage", &mild).unwrap_err();
    assert_eq!(error.arg.as_deref(), Some("voltage_v"));
    let extra = FaultArgs::new().with("voltage_v", FaultArgValue::Number(50.0));
    assert!(calm.inject("overload", &extra).is_err());
    let unknown = calm.inject("melted", &FaultArgs::new()).unwrap_err();
    assert!(unknown.message.contains("comm_lost"), "{}", unknown.message);
    assert!(calm.is_enabled());
    assert_eq!(calm.fault_table().len(), 7);
}

#[test]
fn the_side_door_temperature_and_thresholds_trip_at_the_next_tick() {
    // A coil heated past OT_Value latches C at the next tick.
    let mut m = holding();
    m.set_temperature(130.0);
    assert!(m.is_enabled());
    run(&mut m, 1);
    assert_eq!(refresh(&mut m).state, 0xC);
    // A host raising UV_Value above the 24 V supply trips under-voltage.
    let mut m = holding();
    one(write(&mut m, rid::UV_VALUE, 30.0f32.to_le_bytes()));
    run(&mut m, 1);
    assert_eq!(refresh(&mut m).state, 0x9);
    one(write(&mut m, rid::UV_VALUE, 12.0f32.to_le_bytes()));
    assert_eq!(special(&mut m, Special::ClearError).state, 0);
}
