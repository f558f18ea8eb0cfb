//! The firmware's kinematics as the emulator uses it: flange pose and IK under the profile's
//! DH model (spec §12). Thin adapter so the firmware core does not depend on the kinematics
//! module's exact signatures.

use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};

use super::pose::pose_error;
use super::profile::FirmwareProfile;

/// Modified-DH rows (a mm, α rad, d mm) of spec §12.
const DH_A_MM: [f64; 6] = [0.0, 0.0, 285.03, -21.98, 0.0, 0.0];
const DH_ALPHA_RAD: [f64; 6] = [
    0.0,
    -std::f64::consts::FRAC_PI_2,
    0.0,
    std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    std::f64::consts::FRAC_PI_2,
];
const DH_D_MM: [f64; 6] = [123.0, 0.0, 0.0, 250.75, 0.0, 91.0];

fn theta_offset_deg(dh_offset: bool) -> [f64; 6] {
    if dh_offset {
        [0.0, -172.22, -102.78, 0.0, 0.0, 0.0]
    } else {
        [0.0, -174.22, -100.78, 0.0, 0.0, 0.0]
    }
}

/// Flange pose (m, rad) at reported joint angles `q` under `profile`'s DH table.
pub fn flange(q: &[f64; 6], profile: FirmwareProfile) -> Isometry3<f64> {
    link_frames(q, profile)[5]
}

/// Pose of each of the six DH link frames (the last one is the flange).
pub fn link_frames(q: &[f64; 6], profile: FirmwareProfile) -> [Isometry3<f64>; 6] {
    let offsets = theta_offset_deg(profile.dh_offset());
    let mut t = Isometry3::identity();
    let mut frames = [Isometry3::identity(); 6];
    for i in 0..6 {
        let rot_x = Isometry3::from_parts(
            Translation3::new(DH_A_MM[i] * 1e-3, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), DH_ALPHA_RAD[i]),
        );
        let rot_z = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, DH_D_MM[i] * 1e-3),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), offsets[i].to_radians() + q[i]),
        );
        t = t * rot_x * rot_z;
        frames[i] = t;
    }
    frames
}

/// Numeric IK (damped least squares from `seed`, then a few restarts) within `limits` (rad).
/// `None` when no solution within 0.1 mm / 0.05° exists inside the limits.
pub fn solve(
    target: &Isometry3<f64>,
    seed: &[f64; 6],
    limits: &[(f64, f64); 6],
    profile: FirmwareProfile,
) -> Option<[f64; 6]> {
    let mut seeds = vec![*seed];
    let mid: [f64; 6] = std::array::from_fn(|j| 0.5 * (limits[j].0 + limits[j].1));
    seeds.push(mid);
    for k in 1..=4 {
        let f = f64::from(k) / 5.0;
        seeds.push(std::array::from_fn(|j| {
            limits[j].0 + f * (limits[j].1 - limits[j].0)
        }));
    }
    seeds
        .into_iter()
        .filter_map(|s| descend(target, s, limits, profile))
        .min_by(|a, b| {
            let da: f64 = (0..6).map(|j| (a[j] - seed[j]).powi(2)).sum();
            let db: f64 = (0..6).map(|j| (b[j] - seed[j]).powi(2)).sum();
            da.total_cmp(&db)
        })
}

fn twist_error(target: &Isometry3<f64>, current: &Isometry3<f64>) -> Vector6<f64> {
    let dp = target.translation.vector - current.translation.vector;
    let dr = (target.rotation * current.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

fn descend(
    target: &Isometry3<f64>,
    mut q: [f64; 6],
    limits: &[(f64, f64); 6],
    profile: FirmwareProfile,
) -> Option<[f64; 6]> {
    for _ in 0..200 {
        let current = flange(&q, profile);
        let (ep, er) = pose_error(target, &current);
        if ep < 1e-4 && er < 0.05f64.to_radians() {
            return Some(q);
        }
        let e = twist_error(target, &current);
        let mut jac = Matrix6::zeros();
        let h = 1e-6;
        for j in 0..6 {
            let mut qh = q;
            qh[j] += h;
            let col = twist_error(&flange(&qh, profile), &current) / h;
            jac.set_column(j, &col);
        }
        let lambda2 = 1e-4;
        let jjt = jac * jac.transpose() + Matrix6::identity() * lambda2;
        let dq = jac.transpose() * jjt.lu().solve(&e)?;
        let step = dq.norm();
        let scale = if step > 0.3 { 0.3 / step } else { 1.0 };
        for j in 0..6 {
            q[j] = (q[j] + dq[j] * scale).clamp(limits[j].0, limits[j].1);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::piper::pose::WirePose;

    #[test]
    fn zero_pose_matches_the_spec() {
        let p = WirePose::from_isometry(&flange(&[0.0; 6], FirmwareProfile::V1_8_2));
        assert!((p.position_m[0] * 1000.0 - 56.128).abs() < 0.01, "{p:?}");
        assert!(p.position_m[1].abs() < 1e-9);
        assert!((p.position_m[2] * 1000.0 - 213.266).abs() < 0.01);
        assert!((p.euler_rad[1].to_degrees() - 85.0).abs() < 1e-6);
        let old = WirePose::from_isometry(&flange(&[0.0; 6], FirmwareProfile::V1_5_8));
        assert!((old.position_m[0] * 1000.0 - 54.953).abs() < 0.01);
        assert!((old.position_m[2] * 1000.0 - 203.387).abs() < 0.01);
    }

    #[test]
    fn matches_piper_sdk_fk_at_a_general_pose() {
        // piper_sdk 0.6.2 C_PiperForwardKinematics(1).CalFK at (20, 40, -40, 10, 20, -15)°.
        let q = [20.0f64, 40.0, -40.0, 10.0, 20.0, -15.0].map(f64::to_radians);
        let p = WirePose::from_isometry(&flange(&q, FirmwareProfile::V1_8_2));
        let sdk = [
            133.658_918_9,
            54.399_319_9,
            354.753_859_4,
            -162.653_632_5,
            74.589_777_5,
            -138.527_460_8,
        ];
        for i in 0..3 {
            assert!(
                (p.position_m[i] * 1000.0 - sdk[i]).abs() < 1e-6,
                "{i}: {p:?}"
            );
            assert!(
                (p.euler_rad[i].to_degrees() - sdk[i + 3]).abs() < 1e-6,
                "{i}: {p:?}"
            );
        }
    }

    #[test]
    fn ik_recovers_a_reachable_pose_and_rejects_an_unreachable_one() {
        let limits = [
            (-2.6, 2.6),
            (0.0, 3.14),
            (-2.96, 0.0),
            (-1.55, 1.55),
            (-1.55, 1.55),
            (-3.1, 3.1),
        ];
        let q = [0.3, 1.0, -1.2, 0.2, 0.4, -0.5];
        let target = flange(&q, FirmwareProfile::V1_8_2);
        let sol = solve(
            &target,
            &[0.0, 0.8, -1.0, 0.0, 0.3, 0.0],
            &limits,
            FirmwareProfile::V1_8_2,
        )
        .unwrap();
        let (ep, er) = pose_error(&target, &flange(&sol, FirmwareProfile::V1_8_2));
        assert!(ep < 1e-4 && er < 1e-3);
        let far = Isometry3::translation(2.0, 0.0, 0.2);
        assert!(solve(&far, &q, &limits, FirmwareProfile::V1_8_2).is_none());
    }
}
