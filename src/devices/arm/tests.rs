//! The `arm` grammar and matrix expansion: typed values for good files, errors at the right
//! line for bad ones.

use std::path::Path;

use driver::arm::{AbcErrorCode, Vendor};

use super::model::{ArmAction, ArmCall, ArmCond, MoveArgs};
use crate::devices::{Action, Check, DeviceKind};
use crate::harness::model::{Scenario, StepKind};
use crate::harness::parse_variant;
use crate::harness::test_support::error_of;

const MATRIX: &str =
    "matrix:\n  vendor: [piper, realman]\nbench:\n  devices:\n    arm: {kind: arm}\n";

fn variant(text: &str, value: &str) -> Scenario {
    parse_variant(Path::new("m.yaml"), text, Some(value)).unwrap_or_else(|e| panic!("{e}"))
}

fn vendor(s: &Scenario) -> Vendor {
    match &s.bench.devices[0].kind {
        DeviceKind::Arm(a) => a.vendor,
        other => panic!("not an arm: {other:?}"),
    }
}

#[test]
fn a_matrix_file_loads_once_per_vendor_with_the_vendor_in_the_name() {
    let text = format!("name: moves\n{MATRIX}steps:\n  - arm: {{do: connect}}\n");
    let piper = variant(&text, "piper");
    let realman = variant(&text, "realman");
    assert_eq!(
        (piper.name.as_str(), vendor(&piper)),
        ("moves@piper", Vendor::Piper)
    );
    assert_eq!(
        (realman.name.as_str(), vendor(&realman)),
        ("moves@realman", Vendor::Realman)
    );
    assert_eq!(realman.variant.as_deref(), Some("realman"));
}

#[test]
fn arm_steps_and_conditions_get_their_typed_values() {
    let text = format!(
        "{MATRIX}steps:\n  - arm: {{do: move_joint_position, joints_deg: [1, 2, 3, 4, 5, 6], v: 40, r: 5, trajectory_connect: true, block: false}}\n  - arm: {{do: move_joint_pose, position_m: [0.3, 0, 0.2], euler_deg: [0, 180, 0], expect_code: ARM_OUT_OF_RANGE}}\n  - expect: {{joints_deg: [1, 2, 3, 4, 5, 6], tolerance_deg: 0.5, gripper_actpos: 500}}\n"
    );
    let s = variant(&text, "piper");
    let StepKind::Action {
        action: Action::Arm(ArmAction { call, expect_code }),
        ..
    } = &s.steps[0].kind
    else {
        panic!("{:?}", s.steps[0].kind)
    };
    assert_eq!(
        *call,
        ArmCall::MoveJointPosition(
            vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            MoveArgs {
                v: 40,
                r: 5,
                trajectory_connect: true,
                block: false
            }
        )
    );
    assert_eq!(*expect_code, None);
    let StepKind::Action {
        action: Action::Arm(ArmAction { call, expect_code }),
        ..
    } = &s.steps[1].kind
    else {
        panic!("{:?}", s.steps[1].kind)
    };
    let ArmCall::MoveJointPose(pose, _) = call else {
        panic!("{call:?}")
    };
    assert_eq!(pose.euler_deg, [0.0, 180.0, 0.0]);
    assert_eq!(*expect_code, Some(AbcErrorCode::ArmOutOfRange));
    let StepKind::Expect { checks, .. } = &s.steps[2].kind else {
        panic!("{:?}", s.steps[2].kind)
    };
    assert_eq!(
        checks,
        &vec![
            Check::Arm(ArmCond::Joints(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 0.5)),
            Check::Arm(ArmCond::GripperActpos(500, 10)),
        ]
    );
}

#[test]
fn bad_arm_files_name_the_line() {
    let bench = "bench:\n  devices:\n    arm: {kind: arm, vendor: piper}\nsteps:\n";
    let cases = [
        (
            format!("{bench}  - arm: {{do: move_joint_position, joints_deg: [1, 2, 3]}}\n"),
            "broken.yaml:5:",
            "needs 6 finite angles",
        ),
        (
            format!("{bench}  - arm: {{do: set_arm_stop, v: 20}}\n"),
            "broken.yaml:5:",
            "`v` does not apply to `do: set_arm_stop`",
        ),
        (
            format!("{bench}  - arm: {{do: move_joint_position, joints_deg: [0, 0, 0, 0, 0, 0], v: 101}}\n"),
            "broken.yaml:5:",
            "`v`: 101 out of range",
        ),
        (
            format!("{bench}  - arm: {{do: connect, expect_code: ARM_OUT_OF_REACH}}\n"),
            "broken.yaml:5:",
            "ARM_OUT_OF_REACH",
        ),
        (
            format!("{bench}  - arm: {{do: teleport}}\n"),
            "broken.yaml:5:",
            "teleport",
        ),
        (
            "bench:\n  devices:\n    arm: {kind: arm}\nsteps:\n  - arm: {do: connect}\n".to_owned(),
            "broken.yaml:3:",
            "needs `vendor:`",
        ),
        (
            "bench:\n  devices:\n    arm: {kind: arm, vendor: kuka}\nsteps:\n  - arm: {do: connect}\n"
                .to_owned(),
            "broken.yaml:3:",
            "kuka",
        ),
    ];
    for (text, at, words) in cases {
        let e = error_of(&text);
        assert!(e.starts_with(at), "{e}\n--- for ---\n{text}");
        assert!(e.contains(words), "{e}\n--- for ---\n{text}");
    }
}

#[test]
fn matrix_mistakes_are_reported() {
    let steps = "steps:\n  - arm: {do: connect}\n";
    // Loaded on its own (not through a suite), a matrix file says how it runs.
    let e = error_of(&format!("{MATRIX}{steps}"));
    assert!(e.starts_with("broken.yaml:2:"), "{e}");
    assert!(e.contains("runs once per `vendor` (piper, realman)"), "{e}");
    let two =
        "matrix:\n  vendor: [piper]\n  firmware: [a]\nbench:\n  devices:\n    arm: {kind: arm}\n";
    let e = error_of(&format!("{two}{steps}"));
    assert!(e.contains("exactly one parameter"), "{e}");
    let twice = "matrix:\n  vendor: [piper, piper]\nbench:\n  devices:\n    arm: {kind: arm}\n";
    let e = parse_variant(
        Path::new("m.yaml"),
        &format!("{twice}{steps}"),
        Some("piper"),
    )
    .expect_err("a value listed twice");
    assert!(e.to_string().contains("m.yaml:2:"), "{e}");
    assert!(e.to_string().contains("listed twice"), "{e}");
    let fixed =
        "matrix:\n  vendor: [piper]\nbench:\n  devices:\n    arm: {kind: arm, vendor: realman}\n";
    let e = parse_variant(
        Path::new("m.yaml"),
        &format!("{fixed}{steps}"),
        Some("piper"),
    )
    .expect_err("vendor given twice");
    assert!(e.to_string().contains("set by the file's `matrix:`"), "{e}");
}
