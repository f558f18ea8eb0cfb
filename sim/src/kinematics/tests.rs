//! The shared MDH pieces against hand-evaluated values and finite differences.

use super::*;
use std::f64::consts::FRAC_PI_2;

/// A planar two-link arm (0.3 m, 0.2 m) after a 0.1 m base column.
fn planar() -> [MdhRow; 3] {
    [
        MdhRow::new(0.0, 0.0, 0.1, 0.0),
        MdhRow::new(0.3, 0.0, 0.0, 0.0),
        MdhRow::new(0.2, 0.0, 0.0, 0.0),
    ]
}

#[test]
fn frames_follow_the_rows_and_missing_readings_count_as_zero() {
    let rows = planar();
    let frames: Vec<_> = joint_frames_m(rows, &[FRAC_PI_2, 0.0]).collect();
    assert_eq!(frames.len(), 3);
    // Joint 1 turns the arm to +y; the links lie along it.
    let tip = frames[2].translation.vector;
    assert!((tip - Vector3::new(0.0, 0.5, 0.1)).norm() < 1e-12, "{tip}");
    let elbow = frames[1].translation.vector;
    assert!(
        (elbow - Vector3::new(0.0, 0.3, 0.1)).norm() < 1e-12,
        "{elbow}"
    );
}

#[test]
fn a_row_from_table_units_is_in_metres_and_radians() {
    let row = MdhRow::from_mm_deg(256.0, 90.0, 210.0, -90.0);
    assert_eq!(
        row,
        MdhRow::new(0.256, 90f64.to_radians(), 0.21, -FRAC_PI_2)
    );
    let t = row.transform_m(FRAC_PI_2);
    // Offset and reading cancel; the twist turns d (along z) onto −y.
    let p = t.translation.vector;
    assert!((p - Vector3::new(0.256, -0.21, 0.0)).norm() < 1e-12, "{p}");
}

#[test]
fn jacobian_columns_match_finite_differences() {
    let rows = [
        MdhRow::new(0.0, 0.0, 0.2, 0.0),
        MdhRow::new(0.0, -FRAC_PI_2, 0.0, 0.3),
        MdhRow::new(0.25, 0.0, 0.0, 0.0),
        MdhRow::new(0.0, FRAC_PI_2, 0.2, 0.0),
    ];
    let q = [0.2, -0.4, 0.7, 0.1];
    let tip_of = |q: &[f64]| joint_frames_m(rows, q).last().unwrap();
    let frames: Vec<_> = joint_frames_m(rows, &q).collect();
    let tip = tip_of(&q);
    let h = 1e-7;
    for (i, frame) in frames.iter().enumerate() {
        let (linear, angular) = jacobian_column(frame, &tip.translation.vector);
        let mut moved = q;
        moved[i] += h;
        let (dp, dr) = pose_error(&tip_of(&moved), &tip);
        assert!(
            (linear - dp / h).norm() < 1e-5,
            "joint {i}: {linear} vs {}",
            dp / h
        );
        assert!(
            (angular - dr / h).norm() < 1e-5,
            "joint {i}: {angular} vs {}",
            dr / h
        );
    }
}

#[test]
fn euler_angles_round_trip_away_from_the_singularity() {
    for rpy in [[0.3, -0.5, 2.0], [-2.5, 1.2, -0.7], [0.0, 0.0, 0.0]] {
        let rotation = UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]);
        let got = zyx_euler_rad(&rotation);
        for k in 0..3 {
            assert!((got[k] - rpy[k]).abs() < 1e-12, "{got:?} vs {rpy:?}");
        }
    }
}
