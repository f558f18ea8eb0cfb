//! Unit tests of the URDF model and the rapier world on small rigs with known answers.

use super::*;

/// A horizontal-axis pendulum: a 2 kg point-like bob 0.5 m along +X of the child frame,
/// hinged about Y at 1 m height.
const PENDULUM: &str = r#"<?xml version="1.0"?>
<robot name="pendulum">
  <link name="base"/>
  <link name="arm">
    <inertial>
      <origin xyz="0.5 0 0" rpy="0 0 0"/>
      <mass value="2.0"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/>
    </inertial>
    <collision>
      <origin xyz="0.5 0 0" rpy="0 0 0"/>
      <geometry><sphere radius="0.05"/></geometry>
    </collision>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="base"/>
    <child link="arm"/>
    <origin xyz="0 0 1" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1.0" upper="1.0" effort="20" velocity="3"/>
  </joint>
</robot>"#;

/// A vertical slider carrying 1.5 kg.
const SLIDER: &str = r#"<?xml version="1.0"?>
<robot name="slider">
  <link name="base"><inertial><mass value="1"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <link name="carriage">
    <inertial>
      <origin xyz="0.1 0 0" rpy="0 0 0"/>
      <mass value="1.5"/>
      <inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/>
    </inertial>
  </link>
  <joint name="lift" type="prismatic">
    <parent link="base"/>
    <child link="carriage"/>
    <origin xyz="0 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="100" velocity="1"/>
    <dynamics damping="0.5" friction="0"/>
  </joint>
</robot>"#;

const PIPER: &str = include_str!("../../../urdf/piper.urdf");

fn run(world: &mut RapierWorld, steps: usize, torques: &[f64]) {
    for _ in 0..steps {
        world.step(torques);
    }
}

#[test]
fn pendulum_gravity_torque_matches_the_lever_arm() {
    let model = ArmModel::from_urdf_str(PENDULUM).unwrap();
    // q about +Y: positive q lowers +X (Ry(q) maps X to (cos q, 0, −sin q)).
    for q in [-0.8, -0.3, 0.0, 0.4, 0.9] {
        let tau = model.gravity_torques(&[q], DEFAULT_GRAVITY_M_S2).unwrap()[0];
        // Gravity pushes q positive (down); the motor must push back.
        let expected = -2.0 * 9.81 * 0.5 * f64::cos(q);
        assert!((tau - expected).abs() < 1e-9, "q={q}: {tau} vs {expected}");
    }
    let q = 0.4;
    let pose = model.link_pose("arm", &[q]).unwrap().unwrap();
    let bob = pose * nalgebra::Point3::new(0.5, 0.0, 0.0);
    assert!((bob.x - 0.5 * q.cos()).abs() < 1e-12);
    assert!((bob.z - (1.0 - 0.5 * q.sin())).abs() < 1e-12);
}

#[test]
fn applied_torque_balances_gravity_in_the_world() {
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    for q0 in [-0.5, 0.0, 0.6] {
        world.set_joint_positions(&[q0]).unwrap();
        let hold = world.gravity_torques(&[q0]).unwrap();
        run(&mut world, 500, &hold);
        let q = world.joint_positions()[0];
        assert!((q - q0).abs() < 2e-3, "held at {q0}, drifted to {q}");
        assert!(world.joint_velocities()[0].abs() < 1e-2);
    }
    // 20 % short of the holding torque, the bob must sag (q grows), at about the rate
    // the missing torque predicts: θ'' = Δτ / (m L²).
    world.set_joint_positions(&[0.0]).unwrap();
    let hold = world.gravity_torques(&[0.0]).unwrap()[0];
    run(&mut world, 100, &[0.8 * hold]);
    let q = world.joint_positions()[0];
    let accel = 0.2 * hold.abs() / (2.0 * 0.25 + 1e-4);
    let expected = 0.5 * accel * 0.1 * 0.1;
    assert!(q > 0.0, "the bob must fall, got {q}");
    assert!((q - expected).abs() < 0.15 * expected, "{q} vs {expected}");
}

#[test]
fn slider_holding_force_and_mimic_free_prismatic() {
    let mut world = RapierWorld::from_urdf_str(SLIDER, WorldConfig::default()).unwrap();
    let hold = world.gravity_torques(&[0.0]).unwrap();
    assert!((hold[0] - 1.5 * 9.81).abs() < 1e-9);
    world.set_joint_positions(&[0.1]).unwrap();
    run(&mut world, 500, &hold);
    assert!((world.joint_positions()[0] - 0.1).abs() < 1e-3);
    // Pushing up twice as hard lifts it.
    run(&mut world, 200, &[2.0 * hold[0]]);
    assert!(world.joint_positions()[0] > 0.15);
    assert_eq!(world.joints()[0].damping, 0.5);
}

#[test]
fn external_torques_persist_until_changed() {
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    let hold = world.gravity_torques(&[0.0]).unwrap();
    world.set_external_joint_torques(&[-3.0]);
    run(&mut world, 100, &hold);
    let lifted = world.joint_positions()[0];
    assert!(
        lifted < -0.01,
        "a −3 N·m disturbance lifts the bob, got {lifted}"
    );
    assert_eq!(world.external_joint_torques(), &[-3.0]);
    world.set_external_joint_torques(&[]);
    assert_eq!(world.external_joint_torques(), &[0.0]);
}

#[test]
fn joint_limits_stop_the_joint() {
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    run(&mut world, 3000, &[-15.0]);
    let q = world.joint_positions()[0];
    assert!(q >= -1.0 - 1e-6, "limit −1 rad, got {q}");
    assert!(q < -0.9, "should rest against the stop, got {q}");
}

#[test]
fn input_errors_are_typed() {
    assert!(matches!(
        RapierWorld::from_urdf_str("<robot", WorldConfig::default()),
        Err(PhysicsError::Parse { .. })
    ));
    let bad_step = WorldConfig {
        step_s: 0.0,
        ..WorldConfig::default()
    };
    assert!(matches!(
        RapierWorld::from_urdf_str(PENDULUM, bad_step),
        Err(PhysicsError::InvalidConfig { .. })
    ));
    assert!(matches!(
        RapierWorld::from_urdf_file(
            std::path::Path::new("/nonexistent.urdf"),
            WorldConfig::default()
        ),
        Err(PhysicsError::Io { .. })
    ));
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    assert!(matches!(
        world.set_joint_positions(&[0.0, 0.0]),
        Err(PhysicsError::LengthMismatch {
            expected: 1,
            actual: 2
        })
    ));
    assert!(matches!(
        world.set_joint_positions(&[1.5]),
        Err(PhysicsError::OutOfLimit { .. })
    ));
    assert!(matches!(
        world.set_joint_positions(&[f64::NAN]),
        Err(PhysicsError::NonFinite { .. })
    ));
    let planar = PENDULUM.replace("type=\"revolute\"", "type=\"planar\"");
    assert!(matches!(
        ArmModel::from_urdf_str(&planar),
        Err(PhysicsError::UnsupportedJoint { .. })
    ));
}

#[test]
fn piper_joint_table_is_read_from_the_urdf() {
    let world = RapierWorld::from_urdf_str(PIPER, WorldConfig::default()).unwrap();
    let names: Vec<&str> = world.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6", "joint7", "joint8"]
    );
    let j2 = &world.joints()[1];
    assert_eq!(
        (j2.lower, j2.effort_limit, j2.velocity_limit),
        (0.0, 32.0, 3.0)
    );
    assert_eq!(world.joints()[4].effort_limit, 8.0);
    assert_eq!(world.joints()[6].kind, JointKind::Prismatic);
    let mimic = world.joints()[7].mimic.as_ref().unwrap();
    assert_eq!((mimic.leader_index, mimic.multiplier), (6, -1.0));
    assert!(world.joints()[6].mimic.is_none());
}

#[test]
fn rapier_link_poses_match_our_forward_kinematics() {
    let mut world = RapierWorld::from_urdf_str(PIPER, WorldConfig::default()).unwrap();
    let q = [0.4, 1.2, -1.0, 0.5, -0.6, 0.8, 0.02, -0.02];
    world.set_joint_positions(&q).unwrap();
    let got = world.joint_positions();
    for (a, b) in got.iter().zip(q) {
        assert!((a - b).abs() < 1e-5, "{got:?} vs {q:?}");
    }
    let model_poses = world.model().link_poses(&q).unwrap();
    for (name, expected) in world.model().link_names().iter().zip(&model_poses) {
        let actual = world.link_pose(name).unwrap();
        let dp = (actual.translation.vector - expected.translation.vector).norm();
        let dr = actual.rotation.angle_to(&expected.rotation);
        assert!(dp < 1e-5 && dr < 1e-5, "{name}: {dp} m, {dr} rad");
    }
}

#[test]
fn mimic_follower_tracks_its_leader() {
    let mut world = RapierWorld::from_urdf_str(PIPER, WorldConfig::default()).unwrap();
    let mut q = [0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.01, 0.0];
    world.set_joint_positions(&q).unwrap();
    assert!((world.joint_positions()[7] + 0.01).abs() < 1e-6);
    let mut tau = world.gravity_torques(&q).unwrap();
    tau[6] = 2.0; // open the fingers
    tau[7] = 0.0;
    run(&mut world, 300, &tau);
    let p = world.joint_positions();
    assert!(p[6] > 0.02, "leader opens: {p:?}");
    assert!((p[7] + p[6]).abs() < 1e-3, "follower mirrors: {p:?}");
    q[6] = 0.5; // out of the finger's 35 mm range
    assert!(world.set_joint_positions(&q).is_err());
}

#[test]
fn obstacles_report_contacts_until_removed() {
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    // The bob (r = 5 cm) swings down on a 0.5 m radius from (0, 0, 1); a table whose top is
    // at z = 0.8 under x = 0.3…0.7 catches it at q = asin(0.3) ≈ 0.305 rad.
    let wall = world.add_obstacle(
        ObstacleShape::Box {
            half_extents_m: [0.2, 0.5, 0.4],
        },
        [0.5, 0.0, 0.4],
    );
    assert!(world.contacts().is_empty());
    run(&mut world, 1500, &[0.0]);
    let contacts = world.contacts();
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    assert_eq!(contacts[0].link, "arm");
    assert_eq!(contacts[0].obstacle, wall);
    assert!(contacts[0].normal_force_n > 0.0);
    // Resting on the table, far from its 1 rad limit.
    let q = world.joint_positions()[0];
    assert!((q - 0.3047).abs() < 0.01, "resting at {q}");
    let weight_share = 2.0 * 9.81 * (0.5 * q.cos()) / (0.5 * q.cos());
    assert!(
        (contacts[0].normal_force_n - weight_share).abs() < 0.2 * weight_share,
        "{} N",
        contacts[0].normal_force_n
    );
    world.remove_obstacle(wall);
    run(&mut world, 5, &[0.0]);
    assert!(world.contacts().is_empty());
    let other = world.add_obstacle(ObstacleShape::Sphere { radius_m: 0.1 }, [5.0, 0.0, 0.0]);
    assert_ne!(other, wall, "ids are never reused");
}

#[test]
fn same_inputs_give_the_same_trajectory() {
    let trajectory = || {
        let mut world = RapierWorld::from_urdf_str(PIPER, WorldConfig::default()).unwrap();
        world
            .set_joint_positions(&[0.2, 1.0, -1.2, 0.1, 0.3, 0.0, 0.0, 0.0])
            .unwrap();
        let mut out = Vec::new();
        for k in 0..200 {
            let t = [0.1, 2.0, -1.0, 0.05, 0.0, 0.01 * k as f64, 0.0, 0.0];
            world.step(&t);
            out.extend(world.joint_positions().iter().map(|v| v.to_bits()));
        }
        out
    };
    assert_eq!(trajectory(), trajectory());
}

#[test]
fn time_advances_by_whole_steps() {
    let config = WorldConfig {
        step_s: 0.002,
        ..WorldConfig::default()
    };
    let mut world = RapierWorld::from_urdf_str(PENDULUM, config).unwrap();
    run(&mut world, 250, &[0.0]);
    assert_eq!(world.steps(), 250);
    assert!((world.time_s() - 0.5).abs() < 1e-12);
}

#[test]
fn mass_matrix_diagonal_is_m_l_squared_plus_own_inertia() {
    let model = ArmModel::from_urdf_str(PENDULUM).expect("pendulum");
    // 2 kg at 0.5 m about a Y hinge, plus the bob's own iyy 1e-4.
    let m = model.mass_matrix_diagonal(&[0.3]).expect("diag");
    assert!((m[0] - (2.0 * 0.25 + 1e-4)).abs() < 1e-12, "{m:?}");
    let slider = ArmModel::from_urdf_str(SLIDER).expect("slider");
    let m = slider.mass_matrix_diagonal(&[0.1]).expect("diag");
    assert!((m[0] - 1.5).abs() < 1e-12, "{m:?}");
    // The Piper's full matrix is symmetric positive definite and its kinetic energy
    // ½·q̇ᵀMq̇ matches a finite-difference sum over the links' COM speeds.
    let piper = ArmModel::from_urdf_str(PIPER).expect("piper");
    let q = [0.2, 1.0, -1.0, 0.3, 0.4, 0.5, 0.01, -0.01];
    let m = piper.mass_matrix(&q).expect("M");
    assert!((&m - m.transpose()).amax() < 1e-12);
    assert!(m.clone().cholesky().is_some());
    let qd = [0.3, -0.2, 0.5, 0.1, -0.4, 0.2, 0.0, 0.0];
    let h = 1e-7;
    let q2: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + b * h).collect();
    let (p1, p2) = (
        piper.link_poses(&q).expect("p"),
        piper.link_poses(&q2).expect("p"),
    );
    let mut energy = 0.0;
    for (l, inertial) in piper.inertials().iter().enumerate() {
        let c1 = p1[l] * nalgebra::Point3::from(inertial.com_m);
        let c2 = p2[l] * nalgebra::Point3::from(inertial.com_m);
        let v = (c2 - c1) / h;
        let w = (p2[l].rotation * p1[l].rotation.inverse()).scaled_axis() / h;
        let rot = p1[l].rotation.to_rotation_matrix();
        let i_w = rot.matrix() * inertial.inertia_kg_m2 * rot.matrix().transpose();
        energy += 0.5 * inertial.mass_kg * v.norm_squared() + 0.5 * w.dot(&(i_w * w));
    }
    let qd = nalgebra::DVector::from_column_slice(&qd);
    let from_m = 0.5 * (qd.transpose() * &m * &qd)[(0, 0)];
    assert!(
        (energy - from_m).abs() < 1e-5 * from_m.max(1e-3),
        "{energy} vs {from_m}"
    );
}

#[test]
fn a_torque_beyond_f32_counts_as_zero_instead_of_poisoning_the_world() {
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    // Finite in f64, infinite in rapier's f32.
    world.set_external_joint_torques(&[1e308]);
    assert_eq!(world.external_joint_torques(), &[0.0]);
    for _ in 0..100 {
        world.step(&[-1e300]);
    }
    assert!(world.check_finite().is_ok());
    assert!(world.joint_positions()[0].is_finite());
    assert!(world.joint_velocities()[0].is_finite());
}

#[test]
fn a_diverged_world_says_so_from_then_on() {
    let mut world = RapierWorld::from_urdf_str(PENDULUM, WorldConfig::default()).unwrap();
    assert!(world.check_finite().is_ok());
    // Finite in f32, but its acceleration over a step is not.
    world.set_external_joint_torques(&[3e38]);
    for _ in 0..10 {
        world.step(&[3e38]);
    }
    let err = world.check_finite().unwrap_err();
    assert!(
        matches!(&err, PhysicsError::Diverged { joint, .. } if joint == "hinge"),
        "{err}"
    );
    // Removing the cause does not make a NaN state valid again.
    world.set_external_joint_torques(&[0.0]);
    world.step(&[0.0]);
    assert!(world.check_finite().is_err());
}

#[cfg(unix)]
#[test]
fn a_urdf_path_to_a_device_is_refused_not_read() {
    let err =
        RapierWorld::from_urdf_file(std::path::Path::new("/dev/zero"), WorldConfig::default())
            .unwrap_err();
    assert_eq!(
        err.to_string(),
        "cannot read URDF file /dev/zero: not a regular file"
    );
}

#[test]
fn a_urdf_file_over_the_limit_is_refused_by_its_size() {
    let dir = std::env::temp_dir().join(format!("armhil-urdf-limit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.urdf");
    // Sparse: the size says 16 MiB + 1 without writing it.
    std::fs::File::create(&path)
        .unwrap()
        .set_len(MAX_URDF_BYTES + 1)
        .unwrap();
    let err = ArmModel::from_urdf_file(&path).unwrap_err().to_string();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        err.ends_with("larger than 16 MiB, the limit for a URDF file"),
        "{err}"
    );
}

/// A turntable about the vertical axis (gravity does not load it): 0.5 kg·m² about Z,
/// 1.0 N·m of dry friction.
const TURNTABLE: &str = r#"<?xml version="1.0"?>
<robot name="turntable">
  <link name="base"/>
  <link name="plate">
    <inertial>
      <origin xyz="0 0 0" rpy="0 0 0"/>
      <mass value="5.0"/>
      <inertia ixx="0.5" ixy="0" ixz="0" iyy="0.5" iyz="0" izz="0.5"/>
    </inertial>
  </link>
  <joint name="spin" type="revolute">
    <parent link="base"/>
    <child link="plate"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3.0" upper="3.0" effort="20" velocity="3"/>
    <dynamics damping="0" friction="1.0"/>
  </joint>
</robot>"#;

/// rapier keeps the friction in `f32`: compare to that precision.
fn assert_friction(world: &RapierWorld, joint: usize, expected: f64) {
    let got = world.friction_in_effect(joint).expect("a known joint");
    assert!(
        (got - expected).abs() < 1e-6,
        "friction {got}, expected {expected}"
    );
}

fn turntable(kinetic: Option<f64>) -> RapierWorld {
    let mut world = RapierWorld::from_urdf_str(TURNTABLE, WorldConfig::default()).expect("loads");
    world.set_kinetic_friction(
        0,
        kinetic.map(|k| KineticFriction {
            kinetic: k,
            stick_speed: 0.001,
        }),
    );
    world
}

#[test]
fn a_joint_with_a_kinetic_figure_sticks_at_breakaway_and_slides_at_the_kinetic_value() {
    let mut world = turntable(Some(0.1));
    assert_friction(&world, 0, 1.0);
    // 0.9 N·m is below breakaway: the plate does not move.
    run(&mut world, 500, &[0.9]);
    assert!(
        world.joint_positions()[0].abs() < 1e-6,
        "{:?}",
        world.joint_positions()
    );
    // 1.1 N·m breaks it away; once it slides, only 0.1 N·m of friction is left.
    run(&mut world, 100, &[1.1]);
    assert_friction(&world, 0, 0.1);
    let v0 = world.joint_velocities()[0];
    assert!(v0 > 0.1, "{v0}");
    // 0.5 N·m no longer breaks away from rest, but keeps a sliding plate accelerating at
    // (0.5 − 0.1) / 0.5 = 0.8 rad/s² (a single constant-friction model would brake it).
    run(&mut world, 500, &[0.5]);
    let dv = world.joint_velocities()[0] - v0;
    assert!((dv - 0.4).abs() < 0.02, "Δv {dv} rad/s, expected 0.4");
    // Without torque the kinetic friction stops it, and then the breakaway value holds it.
    run(&mut world, 6000, &[0.0]);
    assert!(world.joint_velocities()[0].abs() < 1e-3);
    assert_friction(&world, 0, 1.0);
    let parked = world.joint_positions()[0];
    run(&mut world, 500, &[0.9]);
    assert!((world.joint_positions()[0] - parked).abs() < 1e-6);
}

#[test]
fn a_joint_without_a_kinetic_figure_keeps_its_urdf_friction_at_every_speed() {
    let mut world = turntable(None);
    assert_eq!(world.kinetic_friction(0), None);
    run(&mut world, 100, &[2.0]);
    assert!(world.joint_velocities()[0] > 0.1);
    assert_friction(&world, 0, 1.0);
    // Sliding at 0.5 N·m it brakes at (1.0 − 0.5) / 0.5 = 1 rad/s².
    let v0 = world.joint_velocities()[0];
    run(&mut world, 100, &[0.5]);
    let dv = world.joint_velocities()[0] - v0;
    assert!((dv + 0.1).abs() < 0.01, "Δv {dv} rad/s, expected −0.1");
    // Clearing a split restores the URDF value; an unknown joint index is ignored.
    let mut split = turntable(Some(0.2));
    split.set_kinetic_friction(0, None);
    split.set_kinetic_friction(7, Some(KineticFriction::new(1.0, 0.1, 0.001)));
    run(&mut split, 100, &[2.0]);
    assert_friction(&split, 0, 1.0);
    assert_eq!(split.friction_in_effect(7), None);
}

#[test]
fn a_collision_mesh_meets_obstacles_as_its_hull_where_its_primitive_would() {
    // The pendulum's bob as a 10 cm STL cube instead of a 5 cm sphere: it rests on the same
    // table with its lower edge, so a little further round (its corner reaches 0.05·√2).
    let tmp = tempfile::tempdir().unwrap();
    let cube = tmp.path().join("bob.stl");
    std::fs::write(
        &cube,
        crate::description::mesh::tests::box_stl_ascii([0.05, 0.05, 0.05]),
    )
    .unwrap();
    let urdf = PENDULUM.replace(
        r#"<geometry><sphere radius="0.05"/></geometry>"#,
        &format!(
            r#"<geometry><mesh filename="{}"/></geometry>"#,
            cube.display()
        ),
    );
    let mut world = RapierWorld::from_urdf_str(&urdf, WorldConfig::default()).unwrap();
    let table = world.add_obstacle(
        ObstacleShape::Box {
            half_extents_m: [0.2, 0.5, 0.4],
        },
        [0.5, 0.0, 0.4],
    );
    run(&mut world, 1500, &[0.0]);
    let contacts = world.contacts();
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    assert_eq!(
        (contacts[0].link.as_str(), contacts[0].obstacle),
        ("arm", table)
    );
    let q = world.joint_positions()[0];
    // Without its mesh the bob would swing through the table to the 1 rad stop.
    assert!(q > 0.2 && q < 0.4, "resting at {q}");
    // The mesh adds no mass (a water-dense cube would add 1 kg): the table carries the 2 kg
    // bob's weight, as for the sphere.
    let weight = 2.0 * 9.81;
    assert!(
        (contacts[0].normal_force_n - weight).abs() < 0.2 * weight,
        "{} N",
        contacts[0].normal_force_n
    );
}
