//! Realman kinematics and planning: FK anchors from the vendor SDK, IK round trips, planner
//! properties.

use std::f64::consts::PI;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use sim::realman::kinematics::{forward, inverse, inverse_with_stats, IkError, Pose};
use sim::realman::model::ArmModel;

fn deg(v: &[f64]) -> Vec<f64> {
    v.iter().map(|d| d.to_radians()).collect()
}

/// Angle difference folded into (−π, π].
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI {
        d - 2.0 * PI
    } else {
        d
    }
}

/// Largest position error (m) and Euler error (rad) of `pose` against an anchor.
fn anchor_error(pose: &Pose, anchor: [f64; 6]) -> (f64, f64) {
    let pos = (0..3)
        .map(|k| (pose.position_m[k] - anchor[k]).abs())
        .fold(0.0, f64::max);
    let ang = (0..3)
        .map(|k| angle_diff(pose.euler_rad[k], anchor[3 + k]).abs())
        .fold(0.0, f64::max);
    (pos, ang)
}

#[test]
fn fk_matches_the_sdk_anchors() {
    // (model, joints in °, SDK pose x, y, z m, rx, ry, rz rad); the non-zero anchors are given
    // to 1e-5 (5 decimals), so they are checked to that rounding.
    let cases: [(ArmModel, Vec<f64>, [f64; 6], f64); 4] = [
        (
            ArmModel::rm65b(),
            vec![0.0; 6],
            [0.0, 0.0, 0.8505, 0.0, 0.0, PI],
            1e-9,
        ),
        (
            ArmModel::rm65b(),
            vec![10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
            [-0.35566, -0.13471, 0.61081, 1.60716, 0.00837, -0.88074],
            5e-6,
        ),
        (
            ArmModel::rm75b(),
            vec![0.0; 7],
            [0.0, 0.0, 0.8505, 0.0, 0.0, 0.0],
            1e-9,
        ),
        (
            ArmModel::rm75b(),
            vec![10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0],
            [0.25648, 0.25244, 0.58010, 1.66686, -0.49573, 2.95871],
            5e-6,
        ),
    ];
    for (model, q, anchor, tol) in cases {
        let pose = forward(&model, &deg(&q));
        let (pos, ang) = anchor_error(&pose, anchor);
        println!(
            "{} q={q:?}: position error {:.3e} mm, angle error {ang:.3e} rad",
            model.name,
            pos * 1000.0
        );
        // 0.01 mm and 1e-5 rad (the brief), and also the anchors' own rounding.
        assert!(pos < 1e-5 && pos <= tol, "{}: {pose:?}", model.name);
        assert!(ang < 1e-5 && ang <= tol, "{}: {pose:?}", model.name);
    }
    // The zero pose reports rz = +π as the SDK does, not −π.
    let z = forward(&ArmModel::rm65b(), &[0.0; 6]);
    assert!((z.euler_rad[2] - PI).abs() < 1e-12, "{z:?}");
}

/// A random joint vector inside 90 % of the limits.
fn random_joints(model: &ArmModel, rng: &mut SmallRng) -> Vec<f64> {
    (0..model.dof)
        .map(|j| {
            let lo = model.joint_min_deg[j].max(-180.0) * 0.9;
            let hi = model.joint_max_deg[j].min(180.0) * 0.9;
            rng.random_range(lo..hi).to_radians()
        })
        .collect()
}

fn pose_distance(a: &Pose, b: &Pose) -> (f64, f64) {
    let pa = a.to_isometry();
    let pb = b.to_isometry();
    let dp = (pa.translation.vector - pb.translation.vector).norm();
    let dr = (pa.rotation * pb.rotation.inverse()).angle();
    (dp, dr)
}

fn round_trip(model: &ArmModel, seed_near: bool, n: usize) -> (usize, usize, usize) {
    let mut rng = SmallRng::seed_from_u64(0x5eed_0065);
    let (mut ok, mut iterations, mut worst_iter) = (0, 0, 0);
    for _ in 0..n {
        let q = random_joints(model, &mut rng);
        let target = forward(model, &q);
        let seed: Vec<f64> = if seed_near {
            q.iter().map(|v| v + rng.random_range(-0.2..0.2)).collect()
        } else {
            vec![0.0, 0.3, 1.2, 0.0, 0.8, 0.0, 0.0][..model.dof].to_vec()
        };
        let (result, stats) = inverse_with_stats(model, &target, &seed);
        iterations += stats.iterations;
        worst_iter = worst_iter.max(stats.iterations);
        // Bounded: at most 9 attempts of 80 iterations.
        assert!(stats.iterations <= 9 * 80, "{stats:?}");
        let Ok(sol) = result else { continue };
        let (dp, dr) = pose_distance(&forward(model, &sol), &target);
        assert!(dp < 1e-5, "round trip off by {} mm", dp * 1000.0);
        assert!(dr < 1e-6, "round trip off by {dr} rad");
        assert_eq!(model.first_out_of_limits(&sol), None, "{sol:?}");
        ok += 1;
    }
    (ok, iterations, worst_iter)
}

#[test]
fn ik_round_trips_at_random_reachable_poses() {
    for model in [ArmModel::rm65b(), ArmModel::rm75b()] {
        let n = 300;
        let (ok_near, it_near, worst_near) = round_trip(&model, true, n);
        let (ok_far, it_far, worst_far) = round_trip(&model, false, n);
        println!(
            "{}: seed near: {ok_near}/{n} solved, {:.1} iterations mean, {worst_near} worst; \
             fixed seed: {ok_far}/{n}, {:.1} mean, {worst_far} worst",
            model.name,
            it_near as f64 / n as f64,
            it_far as f64 / n as f64
        );
        assert_eq!(
            ok_near, n,
            "{}: seeded near the answer must always solve",
            model.name
        );
        assert!(
            ok_far * 100 >= n * 95,
            "{}: {ok_far}/{n} from a fixed seed",
            model.name
        );
    }
}

#[test]
fn ik_refuses_unreachable_poses_quickly() {
    let model = ArmModel::rm65b();
    let seed = vec![0.0; 6];
    for target in [
        Pose::new([2.0, 0.0, 0.3], [0.0, 0.0, 0.0]),
        Pose::new([0.0, 0.0, 0.8506 + 0.01], [0.0, 0.0, PI]),
        Pose::new([0.4, 0.4, 0.0], [PI, 0.0, 0.0]),
    ] {
        let (result, stats) = inverse_with_stats(&model, &target, &seed);
        assert_eq!(result, Err(IkError::NoSolution), "{target:?}");
        assert!(stats.iterations <= 9 * 80, "{stats:?}");
    }
    // Non-finite input is an error, not a panic.
    let bad = Pose::new([f64::NAN, 0.0, 0.3], [0.0; 3]);
    assert!(matches!(
        inverse(&model, &bad, &seed),
        Err(IkError::BadInput { .. })
    ));
    assert!(matches!(
        inverse(&model, &forward(&model, &seed), &[0.0; 3]),
        Err(IkError::BadInput { .. })
    ));
}

#[test]
fn ik_reports_poses_that_need_a_joint_beyond_its_limit() {
    // Elbow folded beyond J3's 135°: the only solutions need |q3| > 135° (the wrist cannot
    // make up the position), so the IK must say which joint.
    let model = ArmModel::rm65b();
    let q = deg(&[0.0, 0.0, 160.0, 0.0, 0.0, 0.0]);
    let mut wide = model.clone();
    wide.joint_max_deg[2] = 179.0;
    wide.joint_min_deg[2] = -179.0;
    let target = forward(&wide, &q);
    let err = inverse(&model, &target, &deg(&[0.0, 0.0, 130.0, 0.0, 0.0, 0.0]));
    match err {
        Err(IkError::OutOfLimits { joint, .. }) => assert_eq!(joint, 2),
        other => panic!("expected OutOfLimits on joint 2, got {other:?}"),
    }
}

#[test]
fn ik_near_singular_configurations() {
    let model = ArmModel::rm65b();
    // Wrist singular (q5 = 0), elbow singular (q3 = 0), shoulder singular (wrist centre on
    // the J1 axis, §13) and slightly off each: the IK either solves exactly or reports
    // NoSolution, within its bound, and never returns a wrong answer.
    let cases = [
        [0.0, 30.0, 60.0, 20.0, 0.0, 10.0],
        [0.0, 30.0, 60.0, 20.0, 0.5, 10.0],
        [10.0, 20.0, 0.0, 30.0, 40.0, 50.0],
        [10.0, 20.0, 0.3, 30.0, 40.0, 50.0],
        [0.0, 43.4, -105.7, 0.0, -30.0, 0.0],
        [0.0, 43.0, -105.7, 0.0, -30.0, 0.0],
        [0.0; 6],
    ];
    for q in cases {
        let q = deg(&q);
        let target = forward(&model, &q);
        let seed: Vec<f64> = q.iter().map(|v| v + 0.05).collect();
        let (result, stats) = inverse_with_stats(&model, &target, &seed);
        assert!(stats.iterations <= 9 * 80);
        let sol = result.unwrap_or_else(|e| panic!("{q:?}: {e}"));
        let (dp, dr) = pose_distance(&forward(&model, &sol), &target);
        assert!(dp < 1e-5 && dr < 1e-6, "{q:?}: {dp} m {dr} rad");
    }
}

mod joint_moves {
    use super::deg;
    use sim::realman::model::ArmModel;
    use sim::realman::planner::{blend, plan_joint, MotionKind, PlanError};

    #[test]
    fn movej_is_synchronised_and_respects_v_percent() {
        let model = ArmModel::rm65b();
        let from = deg(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let to = deg(&[90.0, -45.0, 120.0, 10.0, 30.0, -200.0]);
        for v in [10.0, 50.0, 100.0] {
            let traj = plan_joint(&model, &from, &to, v).expect("plan");
            assert_eq!(traj.kind(), MotionKind::Joint);
            let t_end = traj.duration_s();
            let vmax = model.max_speed_rad_s();
            let mut peak = vec![0.0_f64; 6];
            let n = 2000;
            for i in 0..=n {
                let t = t_end * i as f64 / n as f64;
                let (q, qd) = traj.sample_with_velocity(t);
                // Synchronised: every joint has covered the same fraction of its distance.
                let frac = (q[5] - from[5]) / (to[5] - from[5]);
                for j in 0..6 {
                    let fj = (q[j] - from[j]) / (to[j] - from[j]);
                    assert!((fj - frac).abs() < 1e-9, "t={t} joint {j}");
                    assert!(
                        qd[j].abs() <= vmax[j] * v / 100.0 + 1e-9,
                        "joint {j} too fast"
                    );
                    peak[j] = peak[j].max(qd[j].abs());
                }
            }
            // J6 (200° at 225 °/s) is the critical joint and reaches exactly v % of its limit.
            assert!((peak[5] - vmax[5] * v / 100.0).abs() < 1e-6, "{peak:?}");
            let end = traj.sample(t_end);
            for j in 0..6 {
                assert!((end[j] - to[j]).abs() < 1e-12);
            }
            // Lower bound on the duration: distance / speed of the critical joint.
            assert!(t_end >= 200f64.to_radians() / (vmax[5] * v / 100.0));
            println!("v={v}%: movej takes {t_end:.3} s");
        }
    }

    #[test]
    fn movej_refuses_targets_beyond_the_limits() {
        let model = ArmModel::rm65b();
        let err = plan_joint(
            &model,
            &[0.0; 6],
            &deg(&[0.0, 131.0, 0.0, 0.0, 0.0, 0.0]),
            20.0,
        );
        assert!(
            matches!(err, Err(PlanError::OutOfLimits { joint: 1, .. })),
            "{err:?}"
        );
        let err = plan_joint(&model, &[0.0; 6], &[0.0; 5], 20.0);
        assert!(matches!(err, Err(PlanError::BadInput { .. })));
        let err = plan_joint(&model, &[0.0; 6], &[f64::NAN; 6], 20.0);
        assert!(matches!(err, Err(PlanError::BadInput { .. })));
    }

    #[test]
    fn blending_overlaps_segments_without_jumps() {
        let model = ArmModel::rm65b();
        let a_to = deg(&[30.0, 10.0, 20.0, 0.0, 0.0, 0.0]);
        let b_to = deg(&[30.0, 40.0, 60.0, 0.0, 0.0, 0.0]);
        let a = plan_joint(&model, &[0.0; 6], &a_to, 50.0).expect("a");
        let b = plan_joint(&model, &a_to, &b_to, 50.0).expect("b");
        let plain = blend(&a, &b, 0.0).expect("r=0");
        assert!((plain.duration_s() - a.duration_s() - b.duration_s()).abs() < 1e-12);
        assert_eq!(plain.segment_count(), 2);
        // Back to back: the arm stops at the junction.
        let v_mid = plain.velocity(a.duration_s());
        assert!(v_mid.iter().all(|v| v.abs() < 1e-9), "{v_mid:?}");

        let round = blend(&a, &b, 100.0).expect("r=100");
        assert!(round.duration_s() < plain.duration_s() - 0.05);
        // No stop at the corner, positions continuous, ends at b's end.
        let v_mid = round.velocity(a.duration_s() - 0.05);
        assert!(
            v_mid.iter().map(|v| v.abs()).sum::<f64>() > 0.05,
            "{v_mid:?}"
        );
        let mut last = round.sample(0.0);
        let n = 4000;
        for i in 1..=n {
            let q = round.sample(round.duration_s() * i as f64 / n as f64);
            for j in 0..6 {
                assert!((q[j] - last[j]).abs() < 0.01, "jump at step {i}");
            }
            last = q;
        }
        for j in 0..6 {
            assert!((last[j] - b_to[j]).abs() < 1e-12);
        }
        let ends = round.segment_end_times_s();
        assert_eq!(ends.len(), 2);
        assert!((ends[1] - round.duration_s()).abs() < 1e-12);

        // Segments that do not meet are refused.
        let c = plan_joint(&model, &[0.0; 6], &b_to, 50.0).expect("c");
        assert!(matches!(
            blend(&a, &c, 50.0),
            Err(PlanError::Discontinuous { .. })
        ));
    }
}

mod cartesian_moves {
    use super::{deg, pose_distance};
    use nalgebra::Vector3;
    use sim::realman::kinematics::{forward, forward_isometry, Pose};
    use sim::realman::model::ArmModel;
    use sim::realman::planner::{
        blend, plan_circle, plan_linear, plan_spline, CartesianLimits, MotionKind, PlanError,
        Trajectory,
    };

    fn start() -> (ArmModel, Vec<f64>, Pose) {
        let model = ArmModel::rm65b();
        let q0 = deg(&[0.0, 30.0, 60.0, 0.0, 60.0, 0.0]);
        let p0 = forward(&model, &q0);
        (model, q0, p0)
    }

    fn offset(p: &Pose, d: [f64; 3], r: [f64; 3]) -> Pose {
        Pose::new(
            [
                p.position_m[0] + d[0],
                p.position_m[1] + d[1],
                p.position_m[2] + d[2],
            ],
            [
                p.euler_rad[0] + r[0],
                p.euler_rad[1] + r[1],
                p.euler_rad[2] + r[2],
            ],
        )
    }

    /// Flange positions every millisecond of the trajectory.
    fn flange_track(model: &ArmModel, traj: &Trajectory) -> Vec<Vector3<f64>> {
        let n = (traj.duration_s() * 1000.0).ceil() as usize;
        (0..=n)
            .map(|i| {
                let t = (i as f64 * 0.001).min(traj.duration_s());
                forward_isometry(model, &traj.sample(t)).translation.vector
            })
            .collect()
    }

    #[test]
    fn movel_is_a_straight_line_at_v_percent_of_line_speed() {
        let (model, q0, p0) = start();
        let to = offset(&p0, [0.10, 0.08, -0.12], [0.1, -0.1, 0.2]);
        let limits = CartesianLimits::default();
        let traj = plan_linear(&model, &q0, &to, 50.0, &limits).expect("plan");
        assert_eq!(traj.kind(), MotionKind::Linear);
        let a = Vector3::from(p0.position_m);
        let b = Vector3::from(to.position_m);
        let dir = (b - a).normalize();
        let track = flange_track(&model, &traj);
        let mut worst_off_line = 0.0_f64;
        let mut peak_speed = 0.0_f64;
        for w in track.windows(2) {
            let rel = w[1] - a;
            worst_off_line = worst_off_line.max((rel - dir * rel.dot(&dir)).norm());
            peak_speed = peak_speed.max((w[1] - w[0]).norm() / 0.001);
        }
        println!(
            "movel: {:.3} s, off-line {:.4} mm, peak speed {peak_speed:.4} m/s",
            traj.duration_s(),
            worst_off_line * 1000.0
        );
        assert!(worst_off_line < 1e-5, "{worst_off_line}");
        // 50 % of 0.25 m/s; the last 1 ms step may be a shorter one.
        assert!(peak_speed <= 0.125 * 1.001, "{peak_speed}");
        assert!(peak_speed >= 0.125 * 0.99, "{peak_speed}");
        let (dp, dr) = pose_distance(&forward(&model, &traj.sample(traj.duration_s())), &to);
        assert!(dp < 1e-5 && dr < 1e-6, "{dp} {dr}");
        // The duration is at least distance / speed.
        assert!(traj.duration_s() >= (b - a).norm() / 0.125);
    }

    #[test]
    fn movel_out_of_reach_is_refused_before_moving() {
        let (model, q0, p0) = start();
        let limits = CartesianLimits::default();
        let far = Pose::new([2.0, 0.0, 0.3], p0.euler_rad);
        match plan_linear(&model, &q0, &far, 50.0, &limits) {
            Err(PlanError::Unreachable { fraction, .. }) => assert_eq!(fraction, 1.0),
            other => panic!("expected Unreachable, got {other:?}"),
        }
        let bad = CartesianLimits {
            line_speed_m_s: 0.0,
            ..limits
        };
        let to = offset(&p0, [0.01, 0.0, 0.0], [0.0; 3]);
        assert!(matches!(
            plan_linear(&model, &q0, &to, 50.0, &bad),
            Err(PlanError::BadInput { .. })
        ));
    }

    #[test]
    fn movel_through_the_shoulder_singularity_is_refused() {
        // The doc's shoulder singularity: the wrist centre on the J1 axis. A line that passes
        // it 2 mm to the side needs J1 to swing about 180° within a few millimetres.
        let model = ArmModel::rm65b();
        let singular = deg(&[0.0, 43.4, -105.7, 0.0, -30.0, 0.0]);
        let ps = forward(&model, &singular);
        let at = |dx: f64| offset(&ps, [dx, 0.002, 0.0], [0.0; 3]);
        let q0 = sim::realman::kinematics::inverse(&model, &at(-0.05), &singular).expect("start");
        let err = plan_linear(&model, &q0, &at(0.05), 50.0, &CartesianLimits::default());
        println!(
            "2 mm past the J1 axis: {:?}",
            err.as_ref().map(|t| t.duration_s())
        );
        assert!(
            matches!(err, Err(PlanError::Singular { .. })),
            "{:?}",
            err.err()
        );
    }

    #[test]
    fn movec_follows_the_circle_through_via() {
        let (model, q0, p0) = start();
        let via = offset(&p0, [0.05, 0.05, 0.0], [0.0; 3]);
        let to = offset(&p0, [0.10, 0.0, 0.0], [0.0; 3]);
        let limits = CartesianLimits::default();
        let traj = plan_circle(&model, &q0, &via, &to, 100.0, 0, &limits).expect("plan");
        assert_eq!(traj.kind(), MotionKind::Circle);
        // Centre at p0 + (0.05, 0, 0), radius 0.05.
        let c = Vector3::from(p0.position_m) + Vector3::new(0.05, 0.0, 0.0);
        let track = flange_track(&model, &traj);
        let worst = track
            .iter()
            .map(|p| ((p - c).norm() - 0.05).abs())
            .fold(0.0, f64::max);
        let via_gap = track
            .iter()
            .map(|p| (p - Vector3::from(via.position_m)).norm())
            .fold(f64::INFINITY, f64::min);
        println!(
            "movec: off-circle {:.4} mm, via missed by {:.4} mm",
            worst * 1e3,
            via_gap * 1e3
        );
        assert!(worst < 1e-5 && via_gap < 2e-4);
        let end = track[track.len() - 1];
        assert!((end - Vector3::from(to.position_m)).norm() < 1e-5);

        // One extra loop: 3 half circles instead of 1, so three times the cruise.
        let looped = plan_circle(&model, &q0, &via, &to, 100.0, 1, &limits).expect("loop");
        let cruise = |t: &Trajectory, len: f64| t.duration_s() - len / 0.25;
        let half = std::f64::consts::PI * 0.05;
        assert!((cruise(&traj, half) - cruise(&looped, 3.0 * half)).abs() < 1e-3);

        let collinear = offset(&p0, [0.05, 0.0, 0.0], [0.0; 3]);
        assert_eq!(
            plan_circle(&model, &q0, &collinear, &to, 50.0, 0, &limits),
            Err(PlanError::DegenerateArc)
        );
    }

    #[test]
    fn moves_passes_through_every_point() {
        let (model, q0, p0) = start();
        let pts = [
            offset(&p0, [0.03, 0.03, 0.02], [0.05, 0.0, 0.0]),
            offset(&p0, [0.06, 0.0, 0.04], [0.1, 0.0, 0.0]),
            offset(&p0, [0.09, -0.03, 0.02], [0.1, 0.1, 0.0]),
        ];
        let limits = CartesianLimits::default();
        let traj = plan_spline(&model, &q0, &pts, 80.0, &limits).expect("plan");
        assert_eq!(traj.kind(), MotionKind::Spline);
        let track = flange_track(&model, &traj);
        for p in &pts[..2] {
            let gap = track
                .iter()
                .map(|x| (x - Vector3::from(p.position_m)).norm())
                .fold(f64::INFINITY, f64::min);
            // 1 ms samples at up to 0.2 m/s are 0.2 mm apart.
            assert!(gap < 1.1e-4, "missed a point by {} mm", gap * 1e3);
        }
        let (dp, dr) = pose_distance(&forward(&model, &traj.sample(traj.duration_s())), &pts[2]);
        assert!(dp < 1e-5 && dr < 1e-6);
        assert!(matches!(
            plan_spline(&model, &q0, &pts[..2], 80.0, &limits),
            Err(PlanError::TooFewPoints { needed: 3, got: 2 })
        ));
    }

    #[test]
    fn blended_lines_round_the_corner() {
        let (model, q0, p0) = start();
        let limits = CartesianLimits::default();
        let mid = offset(&p0, [0.1, 0.0, 0.0], [0.0; 3]);
        let end = offset(&p0, [0.1, 0.1, 0.0], [0.0; 3]);
        let a = plan_linear(&model, &q0, &mid, 50.0, &limits).expect("a");
        let b = plan_linear(&model, a.end_rad(), &end, 50.0, &limits).expect("b");
        let sharp = blend(&a, &b, 0.0).expect("sharp");
        let round = blend(&a, &b, 100.0).expect("round");
        assert!(round.duration_s() < sharp.duration_s());
        assert_eq!(round.kind_at(0.0), MotionKind::Linear);
        // The rounded path cuts the corner: it never reaches `mid`.
        let track = flange_track(&model, &round);
        let corner = Vector3::from(mid.position_m);
        let closest = track
            .iter()
            .map(|p| (p - corner).norm())
            .fold(f64::INFINITY, f64::min);
        println!("blend r=100: corner cut by {:.2} mm", closest * 1e3);
        assert!(closest > 1e-3);
        let last = track[track.len() - 1];
        assert!((last - Vector3::from(end.position_m)).norm() < 1e-5);
    }
}

mod mixed {
    use super::{deg, pose_distance};
    use sim::realman::kinematics::{forward, Pose};
    use sim::realman::model::ArmModel;
    use sim::realman::planner::{
        blend, plan_joint_to_pose, plan_linear, CartesianLimits, MotionKind, PlanError,
    };

    #[test]
    fn movej_p_then_movel_report_their_kinds_in_turn() {
        let model = ArmModel::rm65b();
        let q0 = deg(&[0.0, 30.0, 60.0, 0.0, 60.0, 0.0]);
        let p0 = forward(&model, &q0);
        let target = Pose::new(
            [
                p0.position_m[0] + 0.05,
                p0.position_m[1] + 0.1,
                p0.position_m[2],
            ],
            p0.euler_rad,
        );
        let a = plan_joint_to_pose(&model, &q0, &target, 30.0).expect("movej_p");
        assert_eq!(a.kind(), MotionKind::Joint);
        let (dp, dr) = pose_distance(&forward(&model, a.end_rad()), &target);
        assert!(dp < 1e-5 && dr < 1e-6);
        let back = plan_linear(&model, a.end_rad(), &p0, 30.0, &CartesianLimits::default())
            .expect("movel back");
        let both = blend(&a, &back, 30.0).expect("blend");
        assert_eq!(both.kind_at(0.1), MotionKind::Joint);
        assert_eq!(both.kind_at(both.duration_s() - 0.01), MotionKind::Linear);
        let ends = both.segment_end_times_s();
        assert!(
            ends[0] > both.duration_s() - back.duration_s(),
            "segments overlap"
        );
        let far = Pose::new([1.5, 0.0, 0.2], p0.euler_rad);
        assert!(matches!(
            plan_joint_to_pose(&model, &q0, &far, 30.0),
            Err(PlanError::Unreachable { fraction, .. }) if fraction == 1.0
        ));
    }
}

/// The q1 anchor of the fixtures (°).
const Q1_DEG: [f64; 6] = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0];

/// Distance of the RM65-B's wrist centre (where J4, J5, J6 meet: the flange pulled back by its
/// 144 mm along the tool z) from the shoulder (J2 axis on J1), and the most it can be
/// (upper arm a3 + forearm d4), m. A pose whose wrist centre is farther is out of reach
/// whatever the joints.
fn wrist_reach(model: &ArmModel, pose: &Pose) -> (f64, f64) {
    let iso = pose.to_isometry();
    let wrist = iso.translation.vector - iso.rotation * nalgebra::Vector3::z() * model.flange_d_m;
    let shoulder = nalgebra::Vector3::new(0.0, 0.0, model.shoulder_height_m());
    let most = model.mdh[2].a_m.abs() + model.mdh[3].d_m.abs();
    ((wrist - shoulder).norm(), most)
}

#[test]
fn ik_solves_poses_near_q1_seeded_from_q1() {
    // FK(q1) shifted by ±20..50 mm along x, y and z, same orientation, seeded from q1 as the
    // controller does: every pose whose wrist centre is within reach (1 mm margin) solves to
    // 0.01 mm; every one beyond it (q1 is nearly stretched out: 450 of 466 mm) is refused.
    let model = ArmModel::rm65b();
    let q1 = deg(&Q1_DEG);
    let home = forward(&model, &q1);
    let (mut solved, mut refused) = (0, 0);
    for axis in 0..3 {
        for shift_mm in [-50.0, -40.0, -30.0, -20.0, 20.0, 30.0, 40.0, 50.0] {
            let mut target = home;
            target.position_m[axis] += shift_mm * 1e-3;
            let (dist, most) = wrist_reach(&model, &target);
            let (result, stats) = inverse_with_stats(&model, &target, &q1);
            let label = format!("axis {axis} {shift_mm:+} mm (wrist {:.1} mm)", dist * 1e3);
            if dist < most - 1e-3 {
                let sol = result.unwrap_or_else(|e| panic!("{label}: {e}"));
                let (dp, dr) = pose_distance(&forward(&model, &sol), &target);
                assert!(dp < 1e-5 && dr < 1e-6, "{label}: {dp} m {dr} rad");
                assert_eq!(stats.attempts, 1, "{label}: the q1 seed alone must do");
                solved += 1;
            } else if dist > most + 1e-3 {
                assert_eq!(result, Err(IkError::NoSolution), "{label}");
                refused += 1;
            }
        }
    }
    println!("near q1: {solved} solved, {refused} out of reach");
    assert!(
        solved >= 12 && refused >= 3,
        "{solved} solved, {refused} refused"
    );
}

#[test]
fn cartesian_moves_from_q1_plan_below_and_refuse_above() {
    use sim::realman::planner::{
        plan_circle, plan_linear, plan_spline, CartesianLimits, PlanError,
    };
    let model = ArmModel::rm65b();
    let q1 = deg(&Q1_DEG);
    let limits = CartesianLimits::default();
    let at = |dx_mm: f64, dy_mm: f64, dz_mm: f64| {
        let mut p = forward(&model, &q1);
        p.position_m[0] += dx_mm * 1e-3;
        p.position_m[1] += dy_mm * 1e-3;
        p.position_m[2] += dz_mm * 1e-3;
        p
    };
    let ends_at = |traj: &sim::realman::planner::Trajectory, want: &Pose| {
        let (dp, dr) = pose_distance(&forward(&model, &traj.sample(traj.duration_s())), want);
        assert!(dp < 1e-5 && dr < 1e-6, "ends {dp} m {dr} rad off");
    };
    // The motions of the shared vectors: down from q1, where the wrist has room.
    let down = at(0.0, 0.0, -50.0);
    ends_at(
        &plan_linear(&model, &q1, &down, 20.0, &limits).expect("movel"),
        &down,
    );
    let (via, to) = (at(0.0, 30.0, -20.0), at(0.0, 0.0, -40.0));
    ends_at(
        &plan_circle(&model, &q1, &via, &to, 20.0, 0, &limits).expect("movec"),
        &to,
    );
    let points = [
        at(0.0, 0.0, -20.0),
        at(10.0, 10.0, -30.0),
        at(20.0, 0.0, -40.0),
    ];
    ends_at(
        &plan_spline(&model, &q1, &points, 20.0, &limits).expect("moves"),
        &points[2],
    );
    // The same moves mirrored upwards stretch the wrist centre beyond reach: refused at the
    // target, before anything moves.
    let up = at(0.0, 0.0, 50.0);
    assert!(wrist_reach(&model, &up).0 > wrist_reach(&model, &up).1);
    for result in [
        plan_linear(&model, &q1, &up, 20.0, &limits),
        plan_circle(
            &model,
            &q1,
            &at(0.0, 30.0, 20.0),
            &at(0.0, 0.0, 40.0),
            20.0,
            0,
            &limits,
        ),
        plan_spline(
            &model,
            &q1,
            &[
                at(0.0, 0.0, 20.0),
                at(10.0, 10.0, 30.0),
                at(20.0, 0.0, 40.0),
            ],
            20.0,
            &limits,
        ),
    ] {
        match result {
            Err(PlanError::Unreachable { fraction, source }) => {
                assert_eq!(fraction, 1.0);
                assert_eq!(source, IkError::NoSolution);
            }
            other => panic!("expected Unreachable, got {other:?}"),
        }
    }
}
