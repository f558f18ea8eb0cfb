//! FK against values evaluated by hand from the §12 table, IK round trips, URDF consistency.

use super::*;
use crate::physics::ArmModel;

fn assert_pose(p: &FlangePose, xyz_mm: [f64; 3], rpy_deg: [f64; 3], tol_mm: f64) {
    let got = [p.x_mm, p.y_mm, p.z_mm];
    for k in 0..3 {
        assert!((got[k] - xyz_mm[k]).abs() < tol_mm, "{got:?} vs {xyz_mm:?}");
    }
    let ang = p.angles_deg();
    for k in 0..3 {
        let d = (ang[k] - rpy_deg[k] + 180.0).rem_euclid(360.0) - 180.0;
        assert!(d.abs() < 2e-3, "{ang:?} vs {rpy_deg:?}");
    }
}

#[test]
fn zero_pose_matches_the_spec_for_both_variants() {
    // Spec §12 / §4.2: offset = 1 → (56.128, 0, 213.266) mm, (0°, 85°, 0°);
    // offset = 0 → (54.953, 0, 203.387) mm, same orientation.
    let q = [0.0; 6];
    assert_pose(
        &forward(DhVariant::Offset, &q),
        [56.128, 0.0, 213.266],
        [0.0, 85.0, 0.0],
        1e-3,
    );
    assert_pose(
        &forward(DhVariant::NoOffset, &q),
        [54.953, 0.0, 203.387],
        [0.0, 85.0, 0.0],
        1e-3,
    );
}

#[test]
fn zero_pose_by_hand() {
    // At q = 0 the chain is planar in XZ. J2 at z = 123 mm; the upper arm leaves J2 at
    // θ2 = −172.22° in the frame rotated by α2 = −90°, so its direction in the base is
    // (cos θ2, 0, −sin θ2); the forearm adds a3 = 285.03 mm ... evaluated step by step:
    let t2 = (-172.22f64).to_radians();
    let t23 = t2 + (-102.78f64).to_radians();
    // Elbow (frame 3 origin): 285.03 mm along the upper arm.
    let elbow = [285.03 * t2.cos(), 123.0 - 285.03 * t2.sin()];
    // Frame 4: a4 = −21.98 along x3, d4 = 250.75 along z4 = −y3 (α4 = +90°).
    let x3 = [t23.cos(), -t23.sin()];
    let y3 = [-t23.sin(), -t23.cos()];
    let wrist = [
        elbow[0] - 21.98 * x3[0] - 250.75 * y3[0],
        elbow[1] - 21.98 * x3[1] - 250.75 * y3[1],
    ];
    // Frame 6: d6 = 91 along z6; at q4 = q5 = 0 z6 = z4 = −y3.
    let flange = [wrist[0] - 91.0 * y3[0], wrist[1] - 91.0 * y3[1]];
    let p = forward(DhVariant::Offset, &[0.0; 6]);
    assert!((p.x_mm - flange[0]).abs() < 1e-9 && (p.z_mm - flange[1]).abs() < 1e-9);
    assert!(p.y_mm.abs() < 1e-9);
}

#[test]
fn other_poses_match_an_independent_evaluation() {
    // Evaluated from the §12 table with a separate script (plain 4×4 matrices).
    let half_pi = std::f64::consts::FRAC_PI_2;
    let q = [half_pi, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_pose(
        &forward(DhVariant::Offset, &q),
        [0.0, 56.1275, 213.2663],
        [0.0, 85.0, 90.0],
        1e-3,
    );
    let q = [0.3, 1.0, -1.2, 0.4, -0.5, 0.7];
    assert_pose(
        &forward(DhVariant::Offset, &q),
        [176.3433, 36.7657, 534.7728],
        [46.0618, 14.3835, 79.1226],
        1e-3,
    );
    assert_pose(
        &forward(DhVariant::NoOffset, &q),
        [167.7951, 34.1214, 530.4233],
        [46.0618, 14.3835, 79.1226],
        1e-3,
    );
    let q = [-1.0, 2.0, -0.5, -1.2, 1.0, -2.0];
    assert_pose(
        &forward(DhVariant::Offset, &q),
        [44.8282, -201.9082, 66.6480],
        [126.4060, 11.5127, -64.3258],
        1e-3,
    );
}

#[test]
fn euler_convention_round_trips() {
    let pose = FlangePose {
        x_mm: 100.0,
        y_mm: -20.0,
        z_mm: 300.0,
        rx_rad: 0.3,
        ry_rad: -1.1,
        rz_rad: 2.5,
    };
    let back = FlangePose::from_isometry_m(&pose.to_isometry_m());
    for (a, b) in [
        (back.rx_rad, pose.rx_rad),
        (back.ry_rad, pose.ry_rad),
        (back.rz_rad, pose.rz_rad),
        (back.x_mm, pose.x_mm),
    ] {
        assert!((a - b).abs() < 1e-9);
    }
    // R = Rz·Ry·Rx: a pure RY of +90° turns the X axis to −Z.
    let r = rotation_of(&FlangePose {
        ry_rad: std::f64::consts::FRAC_PI_2,
        ..pose
    });
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), pose.rz_rad);
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), pose.rx_rad);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    assert!((r.matrix() - (rz * ry * rx).matrix()).norm() < 1e-12);
}

#[test]
fn ik_of_fk_returns_the_joint_angles() {
    let limits = JointLimits::firmware_default();
    let options = IkOptions::default();
    let poses = [
        [0.3, 1.0, -1.2, 0.4, -0.5, 0.7],
        [-1.0, 2.0, -0.5, -1.2, 1.0, -2.0],
        [0.0, 1.57, -1.3485, 0.3, 0.4, 0.0],
        [2.0, 0.5, -2.5, 0.8, 1.2, 3.0],
    ];
    for q in poses {
        for variant in [DhVariant::Offset, DhVariant::NoOffset] {
            let target = forward(variant, &q);
            let seed: [f64; 6] =
                std::array::from_fn(|i| q[i] + if i % 2 == 0 { 0.08 } else { -0.08 });
            let mut seed = seed;
            limits.clamp(&mut seed);
            let sol = inverse(variant, &target, &seed, &limits, &options).unwrap();
            for i in 0..6 {
                assert!((sol[i] - q[i]).abs() < 1e-4, "{variant:?} {q:?} → {sol:?}");
            }
            let reached = forward(variant, &sol);
            let (dist_mm, angle) = pose_distance(&reached, &target);
            assert!(dist_mm < 1e-3 && angle < 2e-5);
        }
    }
}

#[test]
fn ik_at_the_wrist_singularity_reaches_the_pose() {
    // q5 = 0 aligns J4 and J6: only q4 + q6 is determined.
    let limits = JointLimits::firmware_default();
    let q = [0.0, 1.57, -1.3485, 0.0, 0.0, 0.0];
    let target = forward(DhVariant::Offset, &q);
    let seed = [0.05, 1.5, -1.3, 0.08, 0.05, -0.08];
    let sol = inverse(
        DhVariant::Offset,
        &target,
        &seed,
        &limits,
        &IkOptions::default(),
    )
    .unwrap();
    assert!((sol[3] + sol[5]).abs() < 1e-4, "{sol:?}");
    let (dist_mm, angle) = pose_distance(&forward(DhVariant::Offset, &sol), &target);
    assert!(dist_mm < 1e-3 && angle < 2e-5);
}

#[test]
fn ik_from_a_far_seed_still_reaches_the_pose() {
    let limits = JointLimits::firmware_default();
    let q = [0.5, 1.4, -1.0, 0.2, 0.6, -0.4];
    let target = forward(DhVariant::Offset, &q);
    let sol = inverse(
        DhVariant::Offset,
        &target,
        &[0.0; 6],
        &limits,
        &IkOptions::default(),
    )
    .unwrap();
    assert!(limits.contains(&sol));
    let (dist_mm, angle) = pose_distance(&forward(DhVariant::Offset, &sol), &target);
    assert!(dist_mm < 1e-3 && angle < 2e-5, "{dist_mm} mm {angle} rad");
}

#[test]
fn unreachable_targets_give_no_solution() {
    let limits = JointLimits::firmware_default();
    let far = FlangePose {
        x_mm: 2000.0,
        y_mm: 0.0,
        z_mm: 300.0,
        rx_rad: 0.0,
        ry_rad: 1.5,
        rz_rad: 0.0,
    };
    let err = inverse(
        DhVariant::Offset,
        &far,
        &[0.0; 6],
        &limits,
        &IkOptions::default(),
    )
    .unwrap_err();
    let IkError::NoSolution {
        position_error_mm, ..
    } = err
    else {
        panic!("{err:?}");
    };
    assert!(position_error_mm > 1000.0);
    // Reachable only with J4 at 120°, past its 89° limit.
    let past_limit = forward(DhVariant::Offset, &[0.0, 1.2, -1.2, 2.1, 0.0, 0.0]);
    let tight = JointLimits {
        lower_rad: [-0.1, 1.0, -1.4, -0.2, -0.2, -0.2],
        upper_rad: [0.1, 1.4, -1.0, 0.2, 0.2, 0.2],
    };
    assert!(matches!(
        inverse(
            DhVariant::Offset,
            &past_limit,
            &[0.0, 1.2, -1.2, 0.0, 0.0, 0.0],
            &tight,
            &IkOptions::default()
        ),
        Err(IkError::NoSolution { .. })
    ));
    let nan = FlangePose {
        x_mm: f64::NAN,
        ..far
    };
    assert!(matches!(
        inverse(
            DhVariant::Offset,
            &nan,
            &[0.0; 6],
            &limits,
            &IkOptions::default()
        ),
        Err(IkError::InvalidTarget { .. })
    ));
}

#[test]
fn interpolation_is_straight_and_ends_on_the_targets() {
    let a = forward(DhVariant::Offset, &[0.3, 1.0, -1.2, 0.4, -0.5, 0.7]);
    let b = forward(DhVariant::Offset, &[-0.2, 1.5, -1.0, 0.0, 0.3, 0.0]);
    let (d0, _) = pose_distance(&interpolate(&a, &b, 0.0), &a);
    let (d1, _) = pose_distance(&interpolate(&a, &b, 1.0), &b);
    assert!(d0 < 1e-9 && d1 < 1e-9);
    let mid = interpolate(&a, &b, 0.5);
    assert!((mid.x_mm - 0.5 * (a.x_mm + b.x_mm)).abs() < 1e-9);
    let (_, total) = pose_distance(&a, &b);
    let (_, half) = pose_distance(&a, &mid);
    assert!((half - 0.5 * total).abs() < 1e-9);
}

#[test]
fn urdf_link6_is_the_dh_flange() {
    // The physics world and the firmware FK must agree: the URDF is built on the offset DH.
    let model = ArmModel::from_urdf_str(PIPER_URDF).unwrap();
    for q in [
        [0.0; 6],
        [0.3, 1.0, -1.2, 0.4, -0.5, 0.7],
        [-1.0, 2.0, -0.5, -1.2, 1.0, -2.0],
    ] {
        let mut full = q.to_vec();
        full.extend([0.0, 0.0]); // fingers
        let urdf = model.link_pose("link6", &full).unwrap().unwrap();
        let dh = link_frames_m(DhVariant::Offset, &q)[5];
        let dp = (urdf.translation.vector - dh.translation.vector).norm();
        assert!(dp < 1e-9, "{dp} m");
        assert!(urdf.rotation.angle_to(&dh.rotation) < 1e-9);
        for (i, name) in ["link1", "link2", "link3", "link4", "link5"]
            .iter()
            .enumerate()
        {
            let u = model.link_pose(name, &full).unwrap().unwrap();
            let d = link_frames_m(DhVariant::Offset, &q)[i];
            assert!(
                (u.translation.vector - d.translation.vector).norm() < 1e-9,
                "{name}"
            );
        }
    }
    // The firmware's limits and the URDF's agree.
    let limits = JointLimits::firmware_default();
    for (i, j) in model.joints().iter().take(6).enumerate() {
        assert!((j.lower - limits.lower_rad[i]).abs() < 1e-6, "{}", j.name);
        assert!((j.upper - limits.upper_rad[i]).abs() < 1e-6, "{}", j.name);
    }
}
