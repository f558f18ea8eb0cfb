//! The articulated-body solver against independent references: the model's own mass matrix
//! and gravity torques (Jacobians, no recursion), free fall, conservation of momentum and
//! energy, and a robot coming to rest on the ground.

use nalgebra::{DVector, Point3, Vector3};

use super::ArticulatedWorld;
use crate::physics::conformance::conservative;
use crate::physics::WorldConfig;

const HUMANOID: &str = include_str!("../../../../urdf/humanoid.urdf");
const ARM6: &str = include_str!("../../../../urdf/robstride_arm6.urdf");

fn fixed(urdf: &str) -> ArticulatedWorld {
    ArticulatedWorld::from_urdf_str(urdf, WorldConfig::default()).unwrap()
}

fn floating(urdf: &str, height_m: f64, gravity: [f64; 3]) -> ArticulatedWorld {
    let config = WorldConfig {
        floating_base_height_m: Some(height_m),
        gravity_m_s2: gravity,
        ..WorldConfig::default()
    };
    ArticulatedWorld::from_urdf_str(urdf, config).unwrap()
}

/// A pose inside every joint's limits, different per joint.
fn pose(world: &ArticulatedWorld) -> Vec<f64> {
    world
        .joints()
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let t = ((i * 7 % 11) as f64 / 10.0) * 0.8 + 0.1;
            let (lo, hi) = (j.lower.max(-3.0), j.upper.min(3.0));
            lo + (hi - lo) * t
        })
        .collect()
}

/// Centre of mass of every link together, in the world.
fn centre_of_mass(world: &ArticulatedWorld) -> Vector3<f64> {
    let poses = world.link_poses();
    let mut sum = Vector3::zeros();
    let mut mass = 0.0;
    for (pose, inertial) in poses.iter().zip(world.model().inertials()) {
        sum += (pose * Point3::from(inertial.com_m)).coords * inertial.mass_kg;
        mass += inertial.mass_kg;
    }
    sum / mass
}

#[test]
fn fixed_base_accelerations_are_the_mass_matrix_solution() {
    for urdf in [ARM6, HUMANOID] {
        let mut world = fixed(urdf);
        for (i, _) in world.model().joints().to_vec().iter().enumerate() {
            world.set_armature(i, 0.001 * (i + 1) as f64);
        }
        let q = pose(&world);
        world.set_joint_positions(&q).unwrap();
        let tau: Vec<f64> = (0..q.len()).map(|i| (i as f64 - 3.0) * 0.7).collect();
        // M·q̈ = τ − (torque that holds the arm against gravity), at rest.
        let m = world.model().mass_matrix(&q).unwrap();
        let hold = world
            .model()
            .gravity_torques(&q, crate::physics::DEFAULT_GRAVITY_M_S2)
            .unwrap();
        let rhs = DVector::from_iterator(q.len(), tau.iter().zip(&hold).map(|(t, h)| t - h));
        let expected = m.lu().solve(&rhs).unwrap();
        let (qdd, _) = world.accelerations(&tau, 0.0);
        for (i, (got, want)) in qdd.iter().zip(expected.iter()).enumerate() {
            assert!(
                (got - want).abs() < 1e-6 * (1.0 + want.abs()),
                "joint {i}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn a_free_robot_far_above_the_ground_falls_at_g_without_moving_its_joints() {
    let mut world = floating(HUMANOID, 100.0, crate::physics::DEFAULT_GRAVITY_M_S2);
    let q = pose(&world);
    world.set_joint_positions(&q).unwrap();
    let start = centre_of_mass(&world);
    for _ in 0..100 {
        world.step(&[]);
    }
    let fallen = start.z - centre_of_mass(&world).z;
    // Semi-implicit Euler over 200 substeps of 0.5 ms: g·t²/2 plus half a substep's worth.
    let t = 0.1;
    let exact = 9.81 * t * t / 2.0;
    assert!(
        (fallen - exact).abs() < 9.81 * t * 0.0005,
        "{fallen} vs {exact}"
    );
    for (got, want) in world.joint_positions().iter().zip(&q) {
        assert!(
            (got - want).abs() < 1e-6,
            "a joint moved in free fall: {got} vs {want}"
        );
    }
}

#[test]
fn joint_torques_in_space_do_not_move_the_centre_of_mass() {
    let mut world = floating(HUMANOID, 100.0, [0.0; 3]);
    let start = centre_of_mass(&world);
    let n = world.joints().len();
    let shoulder = world.joint_index("left_shoulder_pitch").unwrap();
    let mut tau = vec![0.0; n];
    tau[shoulder] = 5.0;
    for _ in 0..300 {
        world.step(&tau);
    }
    assert!(
        world.joint_velocities()[shoulder].abs() > 1.0,
        "the torque turns the shoulder"
    );
    let moved = (centre_of_mass(&world) - start).norm();
    // Semi-implicit Euler on a spinning body leaves a little error: 0.03 mm in 0.3 s.
    assert!(moved < 1e-4, "the centre of mass moved {moved} m");
}

#[test]
fn a_swinging_arm_keeps_its_energy_without_damping() {
    // The arm's shoulder, raised 1 rad and let go.
    let mut world = fixed(&conservative(ARM6));
    let mut q = vec![0.0; world.joints().len()];
    q[1] = 1.0;
    world.set_joint_positions(&q).unwrap();
    let mass: f64 = world.model().inertials().iter().map(|i| i.mass_kg).sum();
    let energy = |w: &ArticulatedWorld| {
        let q = w.joint_positions();
        let qd = DVector::from_vec(w.joint_velocities());
        let kinetic = 0.5 * qd.dot(&(w.model().mass_matrix(&q).unwrap() * &qd));
        kinetic + 9.81 * mass * centre_of_mass(w).z
    };
    let start = energy(&world);
    let (mut swing, mut peak_kinetic, mut drift) = (0.0_f64, 0.0_f64, 0.0_f64);
    for _ in 0..500 {
        world.step(&[]);
        swing = swing.max(world.joint_velocities()[1].abs());
        peak_kinetic = peak_kinetic.max(world.kinetic_energy_j());
        drift = drift.max((energy(&world) - start).abs());
    }
    assert!(swing > 1.0, "it swings: {swing} rad/s");
    // Semi-implicit Euler keeps energy within a band that shrinks with the step.
    assert!(
        drift < 0.01 * peak_kinetic,
        "energy drifted by up to {drift} J of {peak_kinetic} J in motion"
    );
}

#[test]
fn an_unpowered_humanoid_falls_and_comes_to_rest_on_the_ground() {
    let mut world = floating(HUMANOID, 0.81, crate::physics::DEFAULT_GRAVITY_M_S2);
    let mut q = vec![0.0; world.joints().len()];
    for (name, value) in [
        ("left_knee", 0.2),
        ("right_knee", 0.2),
        ("left_hip_pitch", -0.1),
        ("right_hip_pitch", -0.1),
        ("left_ankle", -0.1),
        ("right_ankle", -0.1),
    ] {
        q[world.joint_index(name).unwrap()] = value;
    }
    world.set_joint_positions(&q).unwrap();
    let height = |w: &ArticulatedWorld| {
        w.link_poses()[w.model().link_index("trunk").unwrap()]
            .translation
            .z
    };
    for _ in 0..3000 {
        world.step(&[]);
    }
    world.check_finite().unwrap();
    let resting = height(&world);
    assert!(resting < 0.6 && resting > 0.05, "trunk at {resting} m");
    let speed: f64 = world
        .joint_velocities()
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max);
    assert!(speed < 0.05, "still moving at {speed} rad/s");
    for _ in 0..2000 {
        world.step(&[]);
    }
    let creep = (height(&world) - resting).abs();
    assert!(creep < 0.002, "it crept {creep} m in 2 s at rest");
    // Nothing sank through the ground: every link origin stays above it (within a spring's
    // give).
    for pose in world.link_poses() {
        assert!(
            pose.translation.z > -0.01,
            "a link at {} m",
            pose.translation.z
        );
    }
}

#[test]
fn a_free_robot_in_space_keeps_its_kinetic_energy() {
    let mut world = floating(&conservative(HUMANOID), 100.0, [0.0; 3]);
    let n = world.joints().len();
    let mut tau = vec![0.0; n];
    for (i, t) in tau.iter_mut().enumerate() {
        *t = if i % 3 == 0 { 2.0 } else { -1.0 };
    }
    for _ in 0..20 {
        world.step(&tau);
    }
    let start = world.kinetic_energy_j();
    let mut energies = Vec::new();
    for _ in 0..200 {
        world.step(&[]);
        energies.push(world.kinetic_energy_j());
    }
    let worst = energies
        .iter()
        .map(|e| (e - start).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 0.01 * start,
        "energy {start} J changed by up to {worst} J"
    );
}

#[test]
fn absurd_torques_never_panic_and_a_diverged_world_says_which_joint() {
    let mut world = floating(HUMANOID, 0.81, crate::physics::DEFAULT_GRAVITY_M_S2);
    let n = world.joints().len();
    // Alternating torques far beyond any actuator, then values no motor produces.
    for k in 0..200 {
        let tau: Vec<f64> = (0..n)
            .map(|i| if (i + k) % 2 == 0 { 1.0e6 } else { -1.0e6 })
            .collect();
        world.step(&tau);
    }
    world.step(&vec![f64::MAX; n]);
    world.step(&vec![f64::NAN; n]);
    match world.check_finite() {
        Ok(()) => {
            assert!(world.joint_positions().iter().all(|q| q.is_finite()));
            assert!(world.link_poses().iter().all(|p| p
                .translation
                .vector
                .iter()
                .all(|v| v.is_finite())));
        }
        Err(crate::physics::PhysicsError::Diverged { joint, .. }) => {
            let known = world.model().joints().iter().any(|j| j.name == joint)
                || world.model().link_names().contains(&joint);
            assert!(known, "names a joint or the root: {joint}");
        }
        Err(other) => panic!("unexpected error {other}"),
    }
}

/// A free cube of 2 kg whose only collision shape is `collision`.
fn cube_urdf(collision: &str) -> String {
    format!(
        r#"<robot name="cube"><link name="body">
  <inertial><mass value="2"/><inertia ixx="0.013" ixy="0" ixz="0" iyy="0.013" iyz="0" izz="0.013"/></inertial>
  <collision>{collision}</collision></link></robot>"#
    )
}

#[test]
fn a_body_whose_collision_is_a_mesh_rests_on_it_as_on_the_same_box() {
    let tmp = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        (
            "cube.stl",
            crate::description::mesh::tests::box_stl_binary([1.0; 3]),
        ),
        (
            "cube_ascii.STL",
            crate::description::mesh::tests::box_stl_ascii([1.0; 3]).into_bytes(),
        ),
    ] {
        std::fs::write(tmp.path().join(name), bytes).unwrap();
    }
    let rest_height = |collision: &str| {
        let mut world = floating(&cube_urdf(collision), 0.3, [0.0, 0.0, -9.81]);
        for _ in 0..1500 {
            world.step(&[]);
        }
        world.check_finite().unwrap();
        world.link_pose("body").unwrap().translation.z
    };
    let box_height = rest_height(r#"<geometry><box size="0.2 0.2 0.2"/></geometry>"#);
    assert!((box_height - 0.1).abs() < 1e-3, "{box_height}");
    for name in ["cube.stl", "cube_ascii.STL"] {
        // A unit cube scaled to 0.2 m, rotated about z (the ground cares not).
        let mesh = format!(
            r#"<origin rpy="0 0 0.3"/><geometry><mesh filename="{}" scale="0.1 0.1 0.1"/></geometry>"#,
            tmp.path().join(name).display()
        );
        let height = rest_height(&mesh);
        assert!(
            (height - box_height).abs() < 1e-6,
            "{name}: {height} vs {box_height}"
        );
    }
}

#[test]
fn a_mimic_follower_moves_with_its_leader() {
    // A gripper: two fingers on a fixed palm, the right one mirroring the left.
    let urdf = r#"<robot name="gripper">
  <link name="palm"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="left"><inertial><origin xyz="0 0 0.05"/><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-6"/></inertial></link>
  <link name="right"><inertial><origin xyz="0 0 0.05"/><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-6"/></inertial></link>
  <joint name="left_finger" type="revolute"><parent link="palm"/><child link="left"/><origin xyz="0 0.02 0"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="5" velocity="5"/></joint>
  <joint name="right_finger" type="revolute"><parent link="palm"/><child link="right"/><origin xyz="0 -0.02 0"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="5" velocity="5"/>
    <mimic joint="left_finger" multiplier="-1" offset="0.1"/></joint>
</robot>"#;
    let mut world = fixed(urdf);
    world.set_joint_positions(&[0.2, 0.0]).unwrap();
    assert_eq!(world.joint_positions(), vec![0.2, -0.1]);
    let mut moved = 0.0f64;
    for _ in 0..100 {
        // The follower's own torque does nothing: it has no motor of its own.
        world.step(&[0.002, 5.0]);
        let q = world.joint_positions();
        assert!((q[1] - (-q[0] + 0.1)).abs() < 1e-12, "{q:?}");
        moved = moved.max((q[0] - 0.2).abs());
    }
    world.check_finite().unwrap();
    assert!(moved > 0.02, "the leader moved {moved} rad");
}

#[test]
fn the_mass_matrix_diagonal_by_composite_inertias_is_the_models() {
    let mut world = fixed(ARM6);
    let q = [0.3, -0.7, 1.1, 0.4, -0.2, 0.9];
    world.set_armature(2, 0.04);
    world.set_joint_positions(&q).unwrap();
    let reference = world.model().mass_matrix_diagonal(&q).unwrap();
    for (got, want) in world.mass_matrix_diagonal().iter().zip(&reference) {
        assert!(
            (got - want).abs() < 1e-12 * want.max(1.0),
            "{got} vs {want}"
        );
    }
}

#[test]
fn the_base_is_the_trees_root_wherever_the_file_lists_it() {
    // TALOS lists its torso before its base link.
    let urdf = r#"<robot name="r">
  <link name="torso"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="waist" type="revolute"><parent link="base"/><child link="torso"/><origin xyz="0 0 0.072"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="5" velocity="5"/></joint>
</robot>"#;
    let world = floating(urdf, 1.0, [0.0, 0.0, 0.0]);
    assert_eq!(world.model().root_link_name(), "base");
    assert_eq!(world.link_pose("base").unwrap().translation.z, 1.0);
}

#[test]
fn a_long_chain_loads_and_steps() {
    // 2,000 links in a chain: building the tree and the effective inertias is linear.
    let mut urdf = String::from("<robot name=\"chain\">\n");
    for i in 0..2000 {
        urdf.push_str(&format!("<link name=\"l{i}\"><inertial><mass value=\"0.1\"/><inertia ixx=\"1e-4\" ixy=\"0\" ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/></inertial></link>\n"));
        if i > 0 {
            urdf.push_str(&format!("<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/><origin xyz=\"0 0 0.01\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n", i - 1));
        }
    }
    urdf.push_str("</robot>\n");
    let mut world = fixed(&urdf);
    assert_eq!(world.joints().len(), 1999);
    assert_eq!(world.mass_matrix_diagonal().len(), 1999);
    world.step(&[]);
    world.check_finite().unwrap();
}

#[test]
fn with_self_collision_a_swinging_link_stops_on_another_instead_of_passing_through() {
    // A fixed post and, hinged beside it at its top, an arm that falls across it: the arm
    // (a 0.3 m box) swings down on the post's side and, with self-collision on, stops on a
    // stub fixed to the base (a link no joint joins to the arm).
    let urdf = r#"<robot name="stop">
  <link name="base"><inertial><mass value="5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="stub"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <collision><origin xyz="0.2 0 0.8"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="arm"><inertial><origin xyz="0.15 0 0"/><mass value="1"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-2" iyz="0" izz="1e-2"/></inertial>
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision></link>
  <joint name="stub_mount" type="fixed"><parent link="base"/><child link="stub"/></joint>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 1"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="10"/><dynamics damping="0.3"/></joint>
</robot>"#;
    let settle = |self_collision: bool| {
        let description =
            crate::description::Description::parse(urdf.to_owned(), Default::default()).unwrap();
        let geometry = description
            .collision_geometry(crate::description::MissingMeshes::Refuse)
            .unwrap();
        let mut world =
            ArticulatedWorld::from_description(&description, &geometry, WorldConfig::default())
                .unwrap();
        if self_collision {
            assert_eq!(world.enable_self_collision(&geometry, &[]).unwrap(), 1);
        }
        for _ in 0..3000 {
            world.step(&[]);
        }
        world.check_finite().unwrap();
        world.joint_positions()[0]
    };
    // Without: the arm falls to hang straight down (+π/2 about y turns +x onto -z).
    let free = settle(false);
    assert!((free - std::f64::consts::FRAC_PI_2).abs() < 0.05, "{free}");
    // With: it rests on the stub's corner (0.25 m out, 0.15 m below the hinge): the arm's
    // underside (0.02 m below its axis) meets it at atan(0.15/0.25) - asin(0.02/0.2915).
    let stopped = settle(true);
    let corner = (0.15f64 / 0.25).atan() - (0.02f64 / 0.15f64.hypot(0.25)).asin();
    assert!((stopped - corner).abs() < 0.01, "{stopped} vs {corner}");
    // Excluding the pair lets it through again.
    let description =
        crate::description::Description::parse(urdf.to_owned(), Default::default()).unwrap();
    let geometry = description
        .collision_geometry(crate::description::MissingMeshes::Refuse)
        .unwrap();
    let mut world =
        ArticulatedWorld::from_description(&description, &geometry, WorldConfig::default())
            .unwrap();
    let pairs = world
        .enable_self_collision(&geometry, &[("arm".into(), "stub".into())])
        .unwrap();
    assert_eq!(pairs, 0);
    assert!(world
        .enable_self_collision(&geometry, &[("arm".into(), "nope".into())])
        .unwrap_err()
        .to_string()
        .contains("nope"));
}
