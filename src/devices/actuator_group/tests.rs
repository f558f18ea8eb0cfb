//! Unit tests of the actuator-group grammar: joints resolved by name, errors at their places.

use std::path::Path;

use super::model::{GroupAction, GroupCheck, GroupMode, JointTarget};
use crate::devices::{Action, Check, DeviceFault};
use crate::harness::model::{FaultSpec, StepKind};
use crate::harness::parse_scenario;
use crate::harness::test_support::error_of;

const BENCH: &str = "bench:\n  devices:\n    arm:\n      kind: actuator_group\n      actuators:\n        - {joint: shoulder, can_id: 11, model: RS03}\n        - {joint: elbow, can_id: 12, model: RS02}\n";

#[test]
fn joints_are_resolved_by_name_to_their_actuators() {
    let text = format!(
        "{BENCH}steps:\n  - group: {{do: hold, targets_rad: {{elbow: -0.4, shoulder: 0.5}}, kp: 40, kd: 2}}\n  - expect: {{joints_rad: {{elbow: -0.4}}, tolerance_rad: 0.01, enabled_joints: [elbow]}}\n  - inject: {{fault: {{actuator_fault: {{joint: elbow, fault: over_temperature}}}}}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let StepKind::Action {
        action:
            Action::ActuatorGroup(GroupAction::Hold {
                targets,
                kp,
                kd,
                every: None,
            }),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a hold: {:?}", s.steps[0].kind);
    };
    // Actuator 0 is the shoulder, 1 the elbow: the file's order, not the map's.
    assert!(targets.contains(&JointTarget {
        actuator: 0,
        angle_rad: 0.5
    }));
    assert!(targets.contains(&JointTarget {
        actuator: 1,
        angle_rad: -0.4
    }));
    assert_eq!((*kp, *kd), (40.0, 2.0));
    let StepKind::Expect { checks, .. } = &s.steps[1].kind else {
        panic!("not an expect");
    };
    assert_eq!(
        checks[1],
        Check::ActuatorGroup(GroupCheck::EnabledJoints(vec!["elbow".to_owned()]))
    );
    let StepKind::Inject {
        fault:
            FaultSpec::Emulator {
                fault: DeviceFault::ActuatorGroup(f),
                ..
            },
        ..
    } = &s.steps[2].kind
    else {
        panic!("not an actuator fault");
    };
    assert_eq!((f.actuator, f.fault.as_str()), (1, "over_temperature"));
}

#[test]
fn an_unknown_joint_is_named_with_the_groups_joints() {
    let e = error_of(&format!(
        "{BENCH}steps:\n  - group: {{do: hold, targets_rad: {{elbw: 0.1}}, kp: 1, kd: 0}}\n"
    ));
    assert!(e.starts_with("broken.yaml:9:"), "{e}");
    assert!(
        e.contains(
            "unknown joint `elbw`; device `arm` has: shoulder, elbow; did you mean `elbow`?"
        ),
        "{e}"
    );
}

#[test]
fn two_actuators_on_one_can_id_are_refused_at_the_second() {
    let e = error_of(
        "bench:\n  devices:\n    arm:\n      kind: actuator_group\n      actuators:\n        - {joint: a, can_id: 11, model: RS03}\n        - {joint: b, can_id: 11, model: RS02}\nsteps:\n  - group: {do: enable}\n",
    );
    assert!(e.starts_with("broken.yaml:7:"), "{e}");
    assert!(
        e.contains("CAN ID 11 is already joint `a`'s on this bus"),
        "{e}"
    );
}

#[test]
fn an_unknown_fault_gets_the_emulators_message() {
    let e = error_of(&format!(
        "{BENCH}steps:\n  - inject: {{fault: {{actuator_fault: {{joint: elbow, fault: melted}}}}}}\n"
    ));
    assert!(
        e.contains("no RobStride fault `melted`; known: over_temperature"),
        "{e}"
    );
}

/// An actuator's fault takes its values beside `joint` and `fault`, refused at the value.
#[test]
fn an_actuator_fault_takes_its_values() {
    let text = format!(
        "{BENCH}steps:\n  - inject: {{fault: {{actuator_fault: {{joint: elbow, fault: encoder_glitch, counts: 100}}}}}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let StepKind::Inject { fault, .. } = &s.steps[0].kind else {
        panic!("an inject step");
    };
    assert_eq!(fault.describe(), "encoder_glitch 100 counts on joint elbow");
    let e = error_of(&format!(
        "{BENCH}steps:\n  - inject: {{fault: {{actuator_fault: {{joint: elbow, fault: encoder_glitch, counts: 1e9}}}}}}\n"
    ));
    assert!(
        e.contains("`counts`: encoder counts 1000000000 out of range"),
        "{e}"
    );
    let e = error_of(&format!(
        "{BENCH}steps:\n  - inject: {{fault: {{actuator_fault: {{joint: elbow, fault: gate_driver, counts: 1}}}}}}\n"
    ));
    assert!(
        e.contains("fault `gate_driver` takes no arguments, got `counts`"),
        "{e}"
    );
}

/// The repository's `scenarios/robot/` folder, where the robot files' relative paths start.
fn robot_scenario() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robot/x.yaml")
}

#[test]
fn a_robot_group_takes_its_joints_and_buses_from_the_robot_file() {
    let text = "bench:\n  devices:\n    arm:\n      kind: actuator_group\n      robot: ../../robots/robstride_arm6.yaml\nsteps:\n  - group: {do: hold, targets_rad: {flange_roll: 0.2}, kp: 5, kd: 0.1}\n";
    let s = parse_scenario(&robot_scenario(), text).expect("valid");
    let StepKind::Action {
        action: Action::ActuatorGroup(GroupAction::Hold { targets, .. }),
        ..
    } = &s.steps[0].kind
    else {
        panic!("not a hold: {:?}", s.steps[0].kind);
    };
    // flange_roll is the sixth actuator of the robot file, on its second bus.
    assert_eq!(
        targets,
        &[JointTarget {
            actuator: 5,
            angle_rad: 0.2
        }]
    );
}

#[test]
fn a_robot_file_that_does_not_load_is_an_error_at_the_robot_key() {
    let missing = "bench:\n  devices:\n    arm:\n      kind: actuator_group\n      robot: ../../robots/nope.yaml\nsteps: []\n";
    let error = parse_scenario(&robot_scenario(), missing)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("x.yaml:5:14: robot file `../../robots/nope.yaml`"),
        "{error}"
    );
    let both = "bench:\n  devices:\n    arm:\n      kind: actuator_group\n      actuators: [{joint: a, can_id: 1, model: RS03}]\n      robot: ../../robots/robstride_arm6.yaml\nsteps: []\n";
    let error = parse_scenario(&robot_scenario(), both)
        .unwrap_err()
        .to_string();
    assert!(error.contains("x.yaml:6:14: give `actuators`"), "{error}");
}

#[test]
fn streams_modes_moves_watchdogs_and_base_height_are_read_with_their_units() {
    let text = format!(
        "{BENCH}steps:\n  - group: {{do: hold, targets_rad: {{elbow: 0.1}}, kp: 40, kd: 2, every_ms: 10}}\n  - group: {{do: watchdog, window_ms: 100}}\n  - group: {{do: mode, mode: csp}}\n  - group: {{do: move, targets_rad: {{shoulder: 0.6}}, speed_rad_s: 0.5}}\n  - expect: {{base_height_m: 0.8, tolerance_m: 0.01}}\n"
    );
    let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
    let action = |i: usize| match &s.steps[i].kind {
        StepKind::Action {
            action: Action::ActuatorGroup(a),
            ..
        } => a.clone(),
        other => panic!("not a group action: {other:?}"),
    };
    assert!(matches!(
        action(0),
        GroupAction::Hold { every: Some(d), .. } if d == std::time::Duration::from_millis(10)
    ));
    assert_eq!(
        action(1),
        GroupAction::Watchdog {
            window: std::time::Duration::from_millis(100)
        }
    );
    assert_eq!(action(2), GroupAction::Mode(GroupMode::Csp));
    assert_eq!(
        action(3),
        GroupAction::Move {
            targets: vec![JointTarget {
                actuator: 0,
                angle_rad: 0.6
            }],
            speed_rad_s: 0.5
        }
    );
    let StepKind::Expect { checks, .. } = &s.steps[4].kind else {
        panic!("not an expect");
    };
    assert_eq!(
        checks[0],
        Check::ActuatorGroup(GroupCheck::BaseHeight {
            height_m: 0.8,
            tolerance_m: 0.01
        })
    );
}

#[test]
fn a_command_refuses_the_arguments_of_another() {
    assert_eq!(
        error_of(&format!(
            "{BENCH}steps:\n  - group: {{do: move, targets_rad: {{elbow: 0.1}}, speed_rad_s: 1, kp: 3}}\n"
        )),
        "broken.yaml:9:70: `kp` does not apply to `do: move`; it takes: targets_rad, speed_rad_s"
    );
    assert_eq!(
        error_of(&format!(
            "{BENCH}steps:\n  - expect: {{base_height_m: 0.8}}\n"
        )),
        "broken.yaml:9:29: `base_height_m` needs `tolerance_m`"
    );
}

/// A robot's buses carry RobStride frames: the report names them by the robot's actuators
/// (they were left undecoded before the group gave a decoder).
#[test]
fn a_robot_group_decodes_its_actuators_frames_for_reports() {
    let text = "bench:\n  devices:\n    kbot:\n      kind: actuator_group\n      robot: ../../robots/humanoid.yaml\nsteps:\n  - wait_ms: 1\n";
    let s = parse_scenario(&robot_scenario(), text).expect("valid");
    let bench = crate::harness::report::bench_info(&s);
    // Type 2 status of motor 14 (left elbow, RS02, on can0) to the host 0xFD.
    let status = bus::CanFrame::extended(0x0200_0EFD, &[0x80, 0, 0x80, 0, 0x80, 0, 0x01, 0x2C])
        .expect("a frame");
    for bus in [Some("can0"), None, Some("a bus the bench does not have")] {
        let named = bench.decode(bus, &status).expect("the left elbow's status");
        assert_eq!(named.name, "Status");
        assert!(
            named
                .fields
                .iter()
                .any(|f| f.name == "motor" && f.value == "14"),
            "{named:?}"
        );
    }
    // Motor 14 sits on can0: on can1 the frame is no actuator's.
    assert!(bench.decode(Some("can1"), &status).is_none());
    // No actuator has ID 99.
    let stranger = bus::CanFrame::extended(0x0200_63FD, &[0x80, 0, 0x80, 0, 0x80, 0, 0x01, 0x2C])
        .expect("a frame");
    assert!(bench.decode(None, &stranger).is_none());
}

/// The OpenArm's buses carry Damiao frames: the report names them by the robot's motors,
/// each by its own model on its own bus (motor 1 is a DM8009 on both arms; motor 5 a DM4310).
#[test]
fn a_robot_group_decodes_its_damiao_actuators_frames_by_bus_and_id() {
    let text = "bench:\n  devices:\n    openarm:\n      kind: actuator_group\n      robot: ../../robots/openarm.yaml\nsteps:\n  - wait_ms: 1\n";
    let s = parse_scenario(&robot_scenario(), text).expect("valid");
    let bench = crate::harness::report::bench_info(&s);
    // Feedback of ESC_ID 5 on its MST_ID 0x15: enabled, at rest mid-range.
    let feedback = bus::CanFrame::standard(0x015, &[0x15, 0x80, 0x00, 0x80, 0x08, 0x00, 30, 28])
        .expect("a frame");
    for bus in [Some("can0"), Some("can1"), None] {
        let named = bench.decode(bus, &feedback).expect("motor 5's feedback");
        assert_eq!(named.name, "feedback");
        assert!(
            named
                .fields
                .iter()
                .any(|f| f.name == "state" && f.value == "enabled"),
            "{named:?}"
        );
    }
    // No motor commanded on 0x009.
    let enable = [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC];
    let stranger = bus::CanFrame::standard(0x009, &enable).expect("a frame");
    assert!(bench.decode(Some("can0"), &stranger).is_none());
    let named = bench
        .decode(
            Some("can1"),
            &bus::CanFrame::standard(0x001, &enable).expect("a frame"),
        )
        .expect("left_joint1's enable");
    assert_eq!(named.name, "enable");
}

#[test]
fn a_robot_bus_carrying_two_actuator_kinds_is_refused_at_load_naming_both_joints() {
    // The 6-DoF arm with its wrist roll (can1) a Damiao motor beside RobStride wrist motors.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let arm = std::fs::read_to_string(root.join("robots/robstride_arm6.yaml")).unwrap();
    let urdf = root.join("urdf/robstride_arm6.urdf");
    let mixed = arm
        .replace("../urdf/robstride_arm6.urdf", &urdf.display().to_string())
        .replace(
            "{joint: wrist_roll, model: RS02, id: 4, bus: can1}",
            "{joint: wrist_roll, model: DM4310, id: 4, bus: can1}",
        );
    assert_ne!(mixed, arm, "the wrist roll became a Damiao motor");
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("mixed.yaml"), mixed).unwrap();
    let scenario = dir.path().join("x.yaml");
    let text = "bench:\n  devices:\n    arm:\n      kind: actuator_group\n      robot: mixed.yaml\nsteps: []\n";
    let error = parse_scenario(&scenario, text).unwrap_err().to_string();
    assert!(
        error.contains("bus `can1` carries a damiao actuator (joint `wrist_roll`) and a robstride one (joint `wrist_pitch`)"),
        "{error}"
    );
}
