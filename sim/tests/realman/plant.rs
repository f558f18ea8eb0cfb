//! The Realman physical plant: `urdf/rm65b.urdf` against the MDH model, and the joint
//! controllers, brakes and thermal model in the rapier world.

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use sim::physics::{ArmModel as UrdfModel, RapierWorld, WorldConfig};
use sim::realman::kinematics::forward_isometry;
use sim::realman::model::ArmModel;
use sim::realman::planner::plan_joint;
use sim::realman::plant::{
    urdf_for, ArmPlant, PlantError, AMBIENT_C, RM65B_URDF, TORQUE_CONSTANT_NM_PER_A,
};

fn deg(v: &[f64]) -> Vec<f64> {
    v.iter().map(|d| d.to_radians()).collect()
}

#[test]
fn urdf_flange_link_is_the_mdh_flange() {
    for model in [ArmModel::rm65b(), ArmModel::rm75b()] {
        let text = urdf_for(&model).expect("urdf");
        let urdf = UrdfModel::from_urdf_str(text).expect("urdf");
        let mut world = RapierWorld::from_urdf_str(text, WorldConfig::default()).expect("world");
        let tip = format!("Link{}", model.dof);
        let mut rng = SmallRng::seed_from_u64(65);
        let (mut worst_urdf, mut worst_rapier) = (0.0_f64, 0.0_f64);
        for _ in 0..200 {
            let q: Vec<f64> = (0..model.dof)
                .map(|j| {
                    rng.random_range(model.joint_min_deg[j]..model.joint_max_deg[j])
                        .to_radians()
                })
                .collect();
            let mdh = forward_isometry(&model, &q);
            let ours = urdf.link_pose(&tip, &q).expect("fk").expect("tip link");
            let dp = (ours.translation.vector - mdh.translation.vector).norm();
            let dr = (ours.rotation * mdh.rotation.inverse()).angle();
            worst_urdf = worst_urdf.max(dp).max(dr);
            world.set_joint_positions(&q).expect("in limits");
            let rapier = world.link_pose(&tip).expect("tip link");
            let dp = (rapier.translation.vector - mdh.translation.vector).norm();
            let dr = (rapier.rotation * mdh.rotation.inverse()).angle();
            worst_rapier = worst_rapier.max(dp).max(dr);
        }
        println!(
            "{} {tip} vs MDH flange: URDF chain {worst_urdf:.2e}, rapier (f32) {worst_rapier:.2e} (m or rad)",
            model.name
        );
        assert!(worst_urdf < 1e-12, "{worst_urdf}");
        assert!(worst_rapier < 1e-5, "{worst_rapier}");
    }
}

#[test]
fn urdf_limits_efforts_and_masses_match_the_model() {
    for (model, efforts) in [
        (ArmModel::rm65b(), vec![60.0, 60.0, 30.0, 10.0, 10.0, 10.0]),
        (
            ArmModel::rm75b(),
            vec![60.0, 60.0, 30.0, 30.0, 10.0, 10.0, 10.0],
        ),
    ] {
        check_urdf_tables(&model, &efforts);
    }
    // RM65: moving links (CAD table) + base = the spec sheet's 7.2 kg.
    let urdf = UrdfModel::from_urdf_str(RM65B_URDF).expect("urdf");
    let total: f64 = urdf.inertials().iter().map(|i| i.mass_kg).sum();
    assert!((total - 7.2).abs() < 1e-9, "{total}");
}

fn check_urdf_tables(model: &ArmModel, efforts: &[f64]) {
    let urdf = UrdfModel::from_urdf_str(urdf_for(model).expect("urdf")).expect("urdf");
    assert_eq!(urdf.joints().len(), model.dof);
    for (j, info) in urdf.joints().iter().enumerate() {
        assert!((info.lower.to_degrees() - model.joint_min_deg[j]).abs() < 1e-9);
        assert!((info.upper.to_degrees() - model.joint_max_deg[j]).abs() < 1e-9);
        assert_eq!(info.effort_limit, efforts[j]);
        // URDF velocity limits are the spec speeds rounded to 1e-4 rad/s.
        assert!((info.velocity_limit - model.max_speed_deg_s[j].to_radians()).abs() < 1e-4);
        let link = urdf.link_index(&info.child_link).expect("link");
        assert_eq!(urdf.inertials()[link].mass_kg, model.link_masses_kg[j]);
    }
}

/// Streams `traj` to the plant for its duration plus `settle_s`.
fn follow(plant: &mut ArmPlant, traj: &sim::realman::planner::Trajectory, settle_s: f64) {
    let steps = ((traj.duration_s() + settle_s) * 1000.0).ceil() as usize;
    for i in 1..=steps {
        let t = i as f64 * 0.001;
        let (q, v) = traj.sample_with_velocity(t);
        plant.set_target(&q, &v);
        plant.step();
    }
}

#[test]
fn plant_follows_a_planned_movej_to_within_a_tenth_of_a_degree() {
    movej_arrives(
        &ArmModel::rm65b(),
        &deg(&[0.0, 20.0, 40.0, 0.0, 30.0, 0.0]),
        &deg(&[60.0, 80.0, 50.0, -90.0, 70.0, 120.0]),
        &[60.0, 60.0, 30.0, 10.0, 10.0, 10.0],
    );
    movej_arrives(
        &ArmModel::rm75b(),
        &deg(&[0.0, 20.0, 0.0, 40.0, 0.0, 30.0, 0.0]),
        &deg(&[60.0, 70.0, -30.0, 80.0, 90.0, -60.0, 120.0]),
        &[60.0, 60.0, 30.0, 30.0, 10.0, 10.0, 10.0],
    );
}

fn movej_arrives(model: &ArmModel, from: &[f64], to: &[f64], limits: &[f64]) {
    let model = model.clone();
    let (from, to) = (from.to_vec(), to.to_vec());
    let mut plant = ArmPlant::new(&model, &from).expect("plant");
    let traj = plan_joint(&model, &from, &to, 100.0).expect("plan");
    // Tracking error while moving, and arrival error 0.2 s after the plan ends.
    let steps = (traj.duration_s() * 1000.0).ceil() as usize;
    let mut worst_track = 0.0_f64;
    for i in 1..=steps {
        let (q, v) = traj.sample_with_velocity(i as f64 * 0.001);
        plant.set_target(&q, &v);
        plant.step();
        let err = plant
            .positions_rad()
            .iter()
            .zip(&q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        worst_track = worst_track.max(err);
    }
    follow(&mut plant, &traj, 0.2);
    let arrival = plant
        .positions_rad()
        .iter()
        .zip(&to)
        .map(|(a, b)| (a - b).abs().to_degrees())
        .fold(0.0, f64::max);
    println!(
        "{} movej 100 %: {:.3} s, worst tracking error {:.3}°, arrival error {arrival:.4}°",
        model.name,
        traj.duration_s(),
        worst_track.to_degrees()
    );
    assert!(arrival < 0.1, "{arrival}°");
    assert!(plant.speeds_rad_s().iter().all(|v| v.abs() < 1e-3));
    // Effort limits are never exceeded.
    for (t, l) in plant.torques_nm().iter().zip(limits) {
        assert!(t.abs() <= *l);
    }
}

#[test]
fn holding_torque_at_a_horizontal_pose_is_m_g_l() {
    let model = ArmModel::rm65b();
    // J2 at 90°: the stretched arm lies horizontal (checked below through the MDH FK).
    let q = deg(&[0.0, 90.0, 0.0, 0.0, 0.0, 0.0]);
    let flange = forward_isometry(&model, &q).translation.vector;
    assert!(
        (flange.z - 0.2405).abs() < 1e-9 && (flange.norm() - 0.2405f64.hypot(0.61)).abs() < 1e-9
    );
    let mut plant = ArmPlant::new(&model, &q).expect("plant");
    for _ in 0..1000 {
        plant.set_target(&q, &[0.0; 6]);
        plant.step();
    }
    // Independent lever arms: each link's COM distance from the J2 axis along the stretched
    // arm, from the URDF's inertial origins and the link lengths 256 / 210 / 144 mm.
    let urdf = UrdfModel::from_urdf_str(RM65B_URDF).expect("urdf");
    let com = |name: &str| {
        let l = urdf.link_index(name).expect("link");
        (urdf.inertials()[l].mass_kg, urdf.inertials()[l].com_m)
    };
    let (m2, c2) = com("Link2");
    let (m3, c3) = com("Link3");
    let (m4, c4) = com("Link4");
    let (m5, c5) = com("Link5");
    let (m6, c6) = com("Link6");
    // Link2 runs along +x, Link3 and Link5 along −y, Link4 and Link6 along +z of their frames.
    let j2_moment = m2 * c2.x
        + m3 * (0.256 - c3.y)
        + m4 * (0.256 + 0.21 + c4.z)
        + m5 * (0.466 - c5.y)
        + m6 * (0.61 + c6.z);
    let j3_moment = m3 * (-c3.y) + m4 * (0.21 + c4.z) + m5 * (0.21 - c5.y) + m6 * (0.354 + c6.z);
    let g = 9.81;
    let tau = plant.torques_nm();
    println!(
        "holding at J2 = 90°: J2 {:.3} N·m (m·g·l {:.3}), J3 {:.3} N·m (m·g·l {:.3})",
        tau[1],
        g * j2_moment,
        tau[2],
        g * j3_moment
    );
    assert!((tau[1].abs() - g * j2_moment).abs() < 0.05 * g * j2_moment);
    assert!((tau[2].abs() - g * j3_moment).abs() < 0.05 * g * j3_moment);
    // J1's axis is vertical: no gravity load.
    assert!(tau[0].abs() < 0.05, "{tau:?}");
    // Current follows the assumed torque constant.
    let i = plant.currents_ma();
    assert!((i[1] - tau[1] / TORQUE_CONSTANT_NM_PER_A[1] * 1000.0).abs() < 1e-9);
    let held = plant.positions_rad();
    assert!((held[1] - q[1]).abs().to_degrees() < 0.01);
}

#[test]
fn brakes_hold_the_arm_with_the_motors_off() {
    let model = ArmModel::rm65b();
    let q = deg(&[0.0, 60.0, 30.0, 0.0, 40.0, 0.0]);
    let mut plant = ArmPlant::new(&model, &q).expect("plant");
    plant.set_brakes(true);
    // A target elsewhere must not move a braked arm.
    let away = deg(&[20.0, 30.0, 10.0, 10.0, 10.0, 10.0]);
    for _ in 0..500 {
        plant.set_target(&away, &[0.0; 6]);
        plant.step();
    }
    let drift = plant
        .positions_rad()
        .iter()
        .zip(&q)
        .map(|(a, b)| (a - b).abs().to_degrees())
        .fold(0.0, f64::max);
    println!("brakes engaged 0.5 s: drift {drift:.4}°");
    assert!(drift < 0.1, "{drift}");
    assert!(plant.torques_nm().iter().all(|t| *t == 0.0));
    assert!(plant.currents_ma().iter().all(|i| *i == 0.0));
    // Released: it holds where it is, then follows the reference again.
    plant.set_brakes(false);
    for _ in 0..200 {
        plant.step();
    }
    assert!((plant.positions_rad()[1] - q[1]).abs().to_degrees() < 0.1);
    assert!(plant.torques_nm()[1].abs() > 1.0);

    // A disabled joint is braked too; the others keep working.
    plant.set_enabled(1, false);
    assert!(plant.is_braked(1) && !plant.is_braked(2));
    let mut target = plant.positions_rad();
    target[1] += 0.3;
    target[2] += 0.2;
    for _ in 0..1000 {
        plant.set_target(&target, &[0.0; 6]);
        plant.step();
    }
    let now = plant.positions_rad();
    assert!((now[1] - q[1]).abs().to_degrees() < 0.2, "{now:?}");
    assert!((now[2] - target[2]).abs().to_degrees() < 0.1, "{now:?}");
    assert_eq!(plant.torques_nm()[1], 0.0);
}

#[test]
fn joints_under_load_warm_up_and_the_bus_sags() {
    let model = ArmModel::rm65b();
    let q = deg(&[0.0, 90.0, 0.0, 0.0, 0.0, 0.0]);
    let mut plant = ArmPlant::new(&model, &q).expect("plant");
    assert!(plant.temperatures_c().iter().all(|t| *t == AMBIENT_C));
    for _ in 0..20_000 {
        plant.step();
    }
    let t = plant.temperatures_c();
    println!(
        "after 20 s holding horizontal: {t:?} °C, bus {:?} V",
        plant.voltages_v()[0]
    );
    // J2 carries ~11.7 N·m (2.3 A): it warms; J1 carries nothing and stays at ambient.
    assert!(t[1] > AMBIENT_C + 0.05, "{t:?}");
    assert!((t[0] - AMBIENT_C).abs() < 1e-3, "{t:?}");
    let v = plant.voltages_v()[0];
    assert!(v < 48.0 && v > 47.5, "{v}");
}

#[test]
fn bad_inputs_are_refused_or_ignored() {
    let model = ArmModel::rm65b();
    assert!(matches!(
        ArmPlant::new(&model, &[0.0; 5]),
        Err(PlantError::Physics(_))
    ));
    assert!(matches!(
        ArmPlant::new(&model, &deg(&[0.0, 140.0, 0.0, 0.0, 0.0, 0.0])),
        Err(PlantError::Physics(_))
    ));
    let mut five = ArmModel::rm65b();
    five.dof = 5;
    assert!(matches!(
        ArmPlant::new(&five, &[0.0; 5]),
        Err(PlantError::NoUrdf { .. })
    ));
    let q = deg(&[0.0, 30.0, 30.0, 0.0, 30.0, 0.0]);
    let mut plant = ArmPlant::new(&model, &q).expect("plant");
    plant.set_target(&[1.0; 3], &[0.0; 6]);
    plant.set_target(&[f64::NAN; 6], &[0.0; 6]);
    plant.set_enabled(17, false);
    plant.set_temperatures_c(&[f64::INFINITY]);
    for _ in 0..300 {
        plant.step();
    }
    assert!((plant.positions_rad()[0] - q[0]).abs() < 1e-3);
    assert!(plant.temperatures_c()[0].is_finite());
}

/// An arm settled where its loops hold it is not stepped (its world's step count stands while
/// its time goes on), reports the same torques and pose, and a new target wakes it and moves
/// it as before.
#[test]
fn a_settled_arm_rests_until_a_target_moves_it() {
    let model = ArmModel::rm65b();
    let start = deg(&[0.0, 20.0, 70.0, 0.0, 60.0, 0.0]);
    let mut plant = ArmPlant::new(&model, &start).expect("plant");
    for _ in 0..2000 {
        plant.step();
    }
    let (pose, torques) = (plant.positions_rad(), plant.torques_nm());
    assert!(
        torques[1].abs() > 1.0,
        "the shoulder carries the arm: {torques:?}"
    );
    let stepped = plant.world().steps();
    for _ in 0..1000 {
        plant.step();
    }
    assert_eq!(
        plant.world().steps(),
        stepped,
        "a settled arm is not stepped"
    );
    assert!((plant.time_s() - 3.0).abs() < 1e-9, "{}", plant.time_s());
    assert_eq!(plant.positions_rad(), pose);
    assert_eq!(plant.torques_nm(), torques);
    // The reference it holds streamed again leaves it at rest; another one wakes it.
    plant.set_target(&start, &[0.0; 6]);
    plant.step();
    assert_eq!(plant.world().steps(), stepped);
    let mut target = pose.clone();
    target[0] += 0.2;
    plant.set_target(&target, &[0.0; 6]);
    for _ in 0..1000 {
        plant.step();
    }
    assert!(plant.world().steps() > stepped);
    assert!((plant.positions_rad()[0] - target[0]).abs() < 1e-3);
}
