//! Robot files: the shipped ones load, and each mistake is named at its place.

use std::path::{Path, PathBuf};

use super::*;
use sim::robot::Base;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// A robot file in a temporary folder beside a copy of the arm's URDF.
fn write(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("urdf/robstride_arm6.urdf"),
        dir.path().join("arm.urdf"),
    )
    .unwrap();
    let file = dir.path().join("robot.yaml");
    std::fs::write(&file, text).unwrap();
    (dir, file)
}

const ARM: &str = "robot: arm
urdf: arm.urdf
buses:
  - {name: can0}
  - {name: can1, bitrate: 500000}
actuators:
  - {joint: shoulder_yaw, model: RS03, id: 1, bus: can0}
  - {joint: shoulder_pitch, model: RS04, id: 2, bus: can0, direction: -1, zero_offset_rad: 0.1}
  - {joint: elbow_pitch, model: RS03, id: 3, bus: can0}
  - {joint: wrist_pitch, model: RS02, id: 1, bus: can1}
start_rad:
  - {joint: shoulder_pitch, rad: 0.5}
";

#[test]
fn a_robot_file_mixes_kinds_and_the_openarm_is_sixteen_damiao_motors() {
    let mixed = ARM.replace(
        "model: RS02, id: 1, bus: can1",
        "model: dm4340, id: 1, bus: can1",
    );
    let (_dir, file) = write(&mixed);
    let robot = load_robot_file(&file).unwrap();
    let kinds: Vec<&str> = robot
        .config
        .actuators
        .iter()
        .map(|a| a.actuator.kind().name)
        .collect();
    assert_eq!(kinds, ["robstride", "robstride", "robstride", "damiao"]);
    assert_eq!(robot.config.actuators[3].actuator.model().name, "DM4340");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/openarm.yaml");
    let openarm = load_robot_file(&file).unwrap();
    let models: Vec<&str> = openarm.config.actuators[..8]
        .iter()
        .map(|a| a.actuator.model().name)
        .collect();
    assert_eq!(
        models,
        ["DM8009", "DM8009", "DM4340", "DM4340", "DM4310", "DM4310", "DM4310", "DM4310"]
    );
    assert_eq!(openarm.config.actuators.len(), 16);
    assert!(openarm
        .config
        .actuators
        .iter()
        .all(|a| a.actuator.kind().name == "damiao"));
    assert!(openarm.warnings.is_empty(), "{:?}", openarm.warnings);
}

fn error_of(text: &str) -> String {
    let (_dir, file) = write(text);
    error_of_file(&file)
}

fn error_of_file(file: &Path) -> String {
    match load_robot_file(file) {
        Err(RobotFileError::Invalid(e)) => {
            format!("{}:{}: {}", e.at.line, e.at.column, e.message)
        }
        other => panic!("expected an invalid file, got {other:?}"),
    }
}

#[test]
fn a_valid_file_becomes_the_emulators_configuration() {
    let (_dir, file) = write(ARM);
    let robot = load_robot_file(&file).unwrap();
    let c = &robot.config;
    assert_eq!(c.base, Base::Fixed);
    assert_eq!(c.buses.len(), 2);
    assert_eq!(c.buses[1].bitrate_bps, 500_000);
    assert_eq!(c.actuators.len(), 4);
    let shoulder = &c.actuators[1];
    assert_eq!(
        (shoulder.direction, shoulder.zero_offset_rad, shoulder.bus),
        (-1.0, 0.1, 0)
    );
    assert_eq!(c.actuators[3].actuator.can_id(), 1);
    assert_eq!(c.actuators[3].bus, 1, "id 1 twice, on two buses");
    assert_eq!(c.start_positions_rad, [("shoulder_pitch".to_string(), 0.5)]);
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
}

#[test]
fn each_mistake_is_named_at_its_line_and_column() {
    let cases = [
        (
            ARM.replace("joint: elbow_pitch", "joint: elbow_pich"),
            "9:13: the URDF has no movable joint `elbow_pich`; did you mean `elbow_pitch`?",
        ),
        (
            ARM.replace("id: 3, bus: can0", "id: 2, bus: can0"),
            "9:43: id 2 is already joint `shoulder_pitch`'s on bus `can0`",
        ),
        (
            ARM.replace("bus: can1}", "bus: can2}"),
            "10:51: no bus `can2` in `buses` (they are: can0, can1); did you mean `can0`?",
        ),
        (
            ARM.replace(
                "  - {joint: wrist_pitch, model: RS02, id: 1, bus: can1}\n",
                "",
            ),
            "5:12: bus `can1` has no actuator on it",
        ),
        (
            ARM.replace("model: RS04", "model: RS09"),
            "8:36: no actuator model `RS09` (known: RS00, RS01",
        ),
        (
            ARM.replace("direction: -1", "direction: 2"),
            "8:71: `direction` must be 1 or -1, got 2",
        ),
        (
            ARM.replace(
                "  - {joint: shoulder_pitch, rad: 0.5}\n",
                "  - {joint: shoulder_pitch, rad: 0.5}\n  - {joint: shoulder_pitch, rad: 0.2}\n",
            ),
            "13:13: joint `shoulder_pitch` is given a start twice",
        ),
        (
            ARM.replace("urdf: arm.urdf", "urdf: missing.urdf"),
            "2:7: the URDF `missing.urdf` does not load",
        ),
        (
            ARM.replace("bitrate: 500000", "bitrate: 400000"),
            "5:27: `bitrate` 400000 is not one an actuator runs at (1000000, 500000, 250000, 200000, 125000)",
        ),
        (
            ARM.replace("robot: arm", "robot: arm\nbase: floating"),
            "2:7: a floating base needs `start_height_m`",
        ),
        (ARM.replace("buses:", "busses:"), "did you mean `buses`?"),
        // A Damiao motor beside RobStride actuators: its kind's ids and bus rates.
        (
            ARM.replace(
                "model: RS02, id: 1, bus: can1",
                "model: DM4310, id: 1279, bus: can1",
            ),
            "10:45: `id` must be 1..=1278 for a damiao actuator, got 1279",
        ),
        (
            ARM.replace("bitrate: 500000", "bitrate: 200000"),
            "10:51: bus `can1` runs at 200000 bit/s; a robstride actuator runs at",
        ),
    ];
    for (text, expected) in cases {
        let error = error_of(&text);
        assert!(
            error.starts_with(expected) || error.contains(expected),
            "expected `{expected}`, got `{error}`"
        );
    }
}

#[test]
fn an_actuator_weaker_than_its_joints_urdf_effort_is_a_warning() {
    let (_dir, file) = write(&ARM.replace("model: RS04", "model: RS03"));
    let robot = load_robot_file(&file).unwrap();
    assert_eq!(robot.warnings.len(), 1);
    assert_eq!(
        robot.warnings[0].to_string(),
        format!(
            "{}:8:36: RS03 peaks at 60 N·m, below joint `shoulder_pitch`'s URDF effort of 120 N·m",
            file.display()
        )
    );
}

#[test]
fn a_start_outside_the_limits_given_or_default_starts_at_the_nearest_limit_with_a_warning() {
    let (dir, file) = write(&ARM.replace("rad: 0.5", "rad: 5.0"));
    let robot = load_robot_file(&file).unwrap();
    assert_eq!(
        robot.warnings.iter().map(|w| format!("{}:{}: {}", w.at.line, w.at.column, w.message)).collect::<Vec<_>>(),
        ["12:34: joint `shoulder_pitch` starts at 2 rad, its nearest limit: the given start 5 rad is outside its limits [-2, 2]"]
    );
    assert_eq!(
        robot.config.start_positions_rad,
        [("shoulder_pitch".to_string(), 2.0)]
    );
    // A joint whose limits exclude 0 and that the file does not name: the same rule.
    let urdf = std::fs::read_to_string(dir.path().join("arm.urdf")).unwrap();
    let shifted = urdf.replace(
        "<limit lower=\"-2.5\" upper=\"2.5\"",
        "<limit lower=\"0.82\" upper=\"2.5\"",
    );
    std::fs::write(dir.path().join("arm.urdf"), shifted).unwrap();
    let robot = load_robot_file(&file).unwrap();
    assert!(
        robot.warnings.iter().any(|w| w.message
            == "joint `elbow_pitch` starts at 0.82 rad, its nearest limit: the default start 0 rad is outside its limits [0.82, 2.5]"),
        "{:?}",
        robot.warnings
    );
    assert!(robot
        .config
        .start_positions_rad
        .contains(&("elbow_pitch".to_string(), 0.82)));
}

#[test]
fn a_problem_inside_the_urdf_names_the_urdfs_line() {
    let (dir, file) = write(ARM);
    let urdf = std::fs::read_to_string(dir.path().join("arm.urdf")).unwrap();
    let reversed = urdf.replace(
        "<limit lower=\"-2.5\" upper=\"2.5\"",
        "<limit lower=\"2.5\" upper=\"-2.5\"",
    );
    std::fs::write(dir.path().join("arm.urdf"), reversed).unwrap();
    let error = error_of_file(&file);
    assert_eq!(
        error,
        "2:7: the URDF `arm.urdf` line 40: joint `elbow_pitch`'s limits are the wrong way round (lower 2.5 > upper -2.5)"
    );
}

#[test]
fn an_actuator_on_a_mimic_follower_is_refused_and_unused_elements_are_summed_up() {
    let (dir, file) = write(ARM);
    let urdf = std::fs::read_to_string(dir.path().join("arm.urdf")).unwrap();
    let mimic = urdf
        .replace(
            "<dynamics damping=\"0.05\" friction=\"0.0\"/>\n  </joint>\n</robot>",
            "<dynamics damping=\"0.05\" friction=\"0.0\"/>\n    <mimic joint=\"wrist_roll\" multiplier=\"-1\"/>\n    <safety_controller k_velocity=\"1\"/>\n  </joint>\n  <transmission name=\"t\"/>\n  <gazebo/>\n  <gazebo/>\n</robot>",
        );
    std::fs::write(dir.path().join("arm.urdf"), mimic).unwrap();
    let with_flange = ARM.replace(
        "  - {joint: wrist_pitch, model: RS02, id: 1, bus: can1}\n",
        "  - {joint: wrist_pitch, model: RS02, id: 1, bus: can1}\n  - {joint: flange_roll, model: RS02, id: 2, bus: can1}\n",
    );
    std::fs::write(&file, &with_flange).unwrap();
    assert_eq!(
        error_of_file(&file),
        "11:13: joint `flange_roll` follows `wrist_roll` through the URDF's <mimic>: it moves with its leader; put the actuator on `wrist_roll`"
    );
    std::fs::write(&file, ARM).unwrap();
    let robot = load_robot_file(&file).unwrap();
    let messages: Vec<&str> = robot.warnings.iter().map(|w| w.message.as_str()).collect();
    assert_eq!(
        messages,
        ["the URDF `arm.urdf`: not simulated: 2 <gazebo>, 1 <joint><safety_controller>, 1 <transmission>"]
    );
}

#[test]
fn collision_meshes_are_found_through_the_packages_map_or_named_with_every_place_searched() {
    let (dir, file) = write(ARM);
    let urdf = std::fs::read_to_string(dir.path().join("arm.urdf")).unwrap();
    let meshed = urdf.replacen(
        "<geometry><cylinder radius=\"0.03\" length=\"0.1\"/></geometry>",
        "<geometry><mesh filename=\"package://arm_description/meshes/flange.stl\" scale=\"0.5 0.5 0.5\"/></geometry>",
        1,
    );
    std::fs::write(dir.path().join("arm.urdf"), meshed).unwrap();
    let error = error_of_file(&file);
    assert!(
        error.starts_with("2:7: the URDF `arm.urdf` line 67: link `flange`'s collision mesh: `package://arm_description/meshes/flange.stl` is not found (no folder is known for package `arm_description`: name it in the robot file's `packages:`, or set ROS_PACKAGE_PATH or AMENT_PREFIX_PATH)"),
        "{error}"
    );
    // Said to go on without it: a warning instead.
    std::fs::write(&file, format!("{ARM}missing_meshes: skip\n")).unwrap();
    let robot = load_robot_file(&file).unwrap();
    assert!(
        robot.warnings[0]
            .message
            .contains("collision mesh left out"),
        "{:?}",
        robot.warnings
    );
    // Found through the robot file's map, read and hulled: a cube of 0.1 m scaled by 0.5.
    let meshes = dir.path().join("desc/meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    let mut stl = String::from("solid c\n");
    for tri in [
        [[-0.1, -0.1, -0.1], [0.1, -0.1, -0.1], [0.1, 0.1, -0.1]],
        [[-0.1, -0.1, 0.1], [0.1, 0.1, 0.1], [-0.1, 0.1, 0.1]],
    ] {
        stl.push_str("facet normal 0 0 0\nouter loop\n");
        for v in tri {
            stl.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        stl.push_str("endloop\nendfacet\n");
    }
    stl.push_str("endsolid c\n");
    std::fs::write(meshes.join("flange.stl"), stl).unwrap();
    std::fs::write(&file, format!("{ARM}packages: {{arm_description: desc}}\n")).unwrap();
    let robot = load_robot_file(&file).unwrap();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
    let geometry = robot.config.collision.as_ref().unwrap();
    let hull = geometry
        .shapes
        .iter()
        .find_map(|s| match &s.shape {
            sim::description::CollisionShape::Hull { points_m, .. } => Some(points_m),
            _ => None,
        })
        .expect("the flange's mesh");
    assert_eq!(hull.len(), 6);
    assert!(
        hull.iter().all(|p| (p.x.abs() - 0.05).abs() < 1e-6),
        "{hull:?}"
    );
    // Split into convex parts when asked (this test mesh is two loose triangles: V-HACD
    // makes a part of each).
    std::fs::write(
        &file,
        format!("{ARM}packages: {{arm_description: desc}}\nconvex_decomposition: [flange]\n"),
    )
    .unwrap();
    let robot = load_robot_file(&file).unwrap();
    let parts = robot
        .config
        .collision
        .as_ref()
        .unwrap()
        .shapes
        .iter()
        .find_map(|s| match &s.shape {
            sim::description::CollisionShape::Hull { parts_m, .. } => Some(parts_m.len()),
            _ => None,
        });
    assert_eq!(parts, Some(2));
    std::fs::write(&file, format!("{ARM}convex_decomposition: [flang]\n")).unwrap();
    assert!(error_of_file(&file)
        .contains("`convex_decomposition`: the URDF has no link `flang`; did you mean `flange`?"));
}

#[test]
fn a_massless_moving_link_is_refused() {
    let (dir, file) = write(ARM);
    let urdf = std::fs::read_to_string(dir.path().join("arm.urdf")).unwrap();
    // A massless link in the middle of the arm is carried by the links beyond it: fine.
    let massless = urdf.replacen("<mass value=\"1.28\"/>", "<mass value=\"0\"/>", 1);
    std::fs::write(dir.path().join("arm.urdf"), &massless).unwrap();
    load_robot_file(&file).unwrap();
    // The last link massless and without inertia: its joint moves nothing.
    let flange = massless.replace(
        "<mass value=\"0.3\"/><inertia ixx=\"0.000318\" iyy=\"0.000318\" izz=\"0.000135\"",
        "<mass value=\"0\"/><inertia ixx=\"0\" iyy=\"0\" izz=\"0\"",
    );
    std::fs::write(dir.path().join("arm.urdf"), flange).unwrap();
    let error = load_robot_file(&file).unwrap_err().to_string();
    assert!(
        error.contains("the URDF `arm.urdf` does not load: joint flange_roll moves nothing with mass or inertia"),
        "{error}"
    );
}

#[test]
fn every_shipped_robot_loads_without_warnings() {
    let mut found = 0;
    for entry in std::fs::read_dir(repo("robots")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "yaml") {
            let robot = load_robot_file(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                robot.warnings.is_empty(),
                "{}: {:?}",
                path.display(),
                robot.warnings
            );
            found += 1;
        }
    }
    assert!(found >= 1);
}

#[test]
fn a_huge_bad_value_is_cut_short_in_the_message_and_its_line_not_shown() {
    let name = "j".repeat(500);
    let (_dir, file) = write(&ARM.replace("joint: elbow_pitch", &format!("joint: {name}")));
    let Err(RobotFileError::Invalid(e)) = load_robot_file(&file) else {
        panic!("expected an invalid file");
    };
    assert!(
        e.message.contains(&format!("`{}…", "j".repeat(39))),
        "{}",
        e.message
    );
    assert!(!e.message.contains(&"j".repeat(41)), "{}", e.message);
    assert_eq!(e.source_line, None, "a 500-character line is not shown");
}

#[test]
fn self_collision_is_off_on_or_on_without_the_pairs_named() {
    let (_dir, file) = write(ARM);
    assert_eq!(load_robot_file(&file).unwrap().config.self_collision, None);
    std::fs::write(&file, format!("{ARM}self_collision: true\n")).unwrap();
    assert_eq!(
        load_robot_file(&file).unwrap().config.self_collision,
        Some(Vec::new())
    );
    std::fs::write(
        &file,
        format!("{ARM}self_collision: [[upper_arm, flange], [base, forearm]]\n"),
    )
    .unwrap();
    assert_eq!(
        load_robot_file(&file).unwrap().config.self_collision,
        Some(vec![
            ("upper_arm".to_string(), "flange".to_string()),
            ("base".to_string(), "forearm".to_string())
        ])
    );
    std::fs::write(
        &file,
        format!("{ARM}self_collision: [[upper_arm, flang]]\n"),
    )
    .unwrap();
    assert_eq!(
        error_of_file(&file),
        "13:17: `self_collision`: the URDF has no link `flang`; did you mean `flange`?"
    );
}

/// `physics:` chooses the solver; rapier's refuses what only the articulated solver does,
/// at the `physics` line, and a misspelt word is named with the nearest one.
#[test]
fn physics_chooses_the_solver_and_rapier_refuses_what_it_cannot_do() {
    let (_dir, file) = write(&ARM.replace("robot: arm", "robot: arm\nphysics: rapier"));
    let robot = load_robot_file(&file).unwrap();
    assert_eq!(robot.config.physics, sim::physics::Solver::Rapier);
    let (_dir, file) = write(ARM);
    assert_eq!(
        load_robot_file(&file).unwrap().config.physics,
        sim::physics::Solver::Articulated
    );
    let cases = [
        (
            ARM.replace("robot: arm", "robot: arm\nphysics: rapir"),
            "2:10: `physics` must be `articulated` or `rapier`, got `rapir`; did you mean `rapier`?",
        ),
        (
            ARM.replace("robot: arm", "robot: arm\nphysics: rapier\nself_collision: true"),
            "2:10: `physics: rapier` has no self-collision",
        ),
        (
            ARM.replace(
                "robot: arm",
                "robot: arm\nphysics: rapier\nbase: floating\nstart_height_m: 1.0\ngantry: until_enabled",
            ),
            "2:10: `physics: rapier` cannot hold a floating base on a gantry",
        ),
    ];
    for (text, expected) in cases {
        let error = error_of(&text);
        assert!(
            error.starts_with(expected),
            "expected `{expected}`, got `{error}`"
        );
    }
}
