//! The firmware's kinematics as the emulator uses it: flange pose and IK under the profile's
//! DH model (spec §12), delegating to [`super::kinematics`] (written by the physics side).

use nalgebra::Isometry3;

use super::kinematics::{self, DhVariant, FlangePose, IkOptions, JointLimits};
use super::profile::FirmwareProfile;

fn variant(profile: FirmwareProfile) -> DhVariant {
    DhVariant::from_offset_flag(profile.dh_offset())
}

/// Flange pose (m, rad) at reported joint angles `q` under `profile`'s DH table.
pub fn flange(q: &[f64; 6], profile: FirmwareProfile) -> Isometry3<f64> {
    link_frames(q, profile)[5]
}

/// Pose of each of the six DH link frames (the last one is the flange), m.
pub fn link_frames(q: &[f64; 6], profile: FirmwareProfile) -> [Isometry3<f64>; 6] {
    kinematics::link_frames_m(variant(profile), q)
}

/// IK within `limits` (rad, reported frame), seeded with `seed`; `None` when no solution
/// exists inside the limits. `coarse` relaxes the tolerance to 0.01 mm / 0.006° for the many
/// samples of a Cartesian path.
pub fn solve(
    target: &Isometry3<f64>,
    seed: &[f64; 6],
    limits: &[(f64, f64); 6],
    profile: FirmwareProfile,
    coarse: bool,
) -> Option<[f64; 6]> {
    let limits = JointLimits {
        lower_rad: limits.map(|l| l.0),
        upper_rad: limits.map(|l| l.1),
    };
    let options = if coarse {
        IkOptions {
            position_tolerance_mm: 0.01,
            orientation_tolerance_rad: 1e-4,
            ..IkOptions::default()
        }
    } else {
        IkOptions::default()
    };
    let goal = FlangePose::from_isometry_m(target);
    kinematics::inverse(variant(profile), &goal, seed, &limits, &options).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::piper::pose::{pose_error, WirePose};

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
            (0.0, 3.1),
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
            false,
        )
        .unwrap();
        let (ep, er) = pose_error(&target, &flange(&sol, FirmwareProfile::V1_8_2));
        assert!(ep < 1e-4 && er < 1e-3);
        let far = Isometry3::translation(2.0, 0.0, 0.2);
        assert!(solve(&far, &q, &limits, FirmwareProfile::V1_8_2, true).is_none());
    }
}
