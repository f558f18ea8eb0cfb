//! Forward kinematics of the Piper from the SDK's modified (Craig) DH table (spec §12),
//! implemented from the table, not from the SDK's code, on the crate's one MDH chain
//! ([`crate::arm::kinematics::Chain`]).

use nalgebra::Isometry3;

use crate::arm::kinematics::{Chain, MdhJoint};

/// Which DH table to use: the firmware's 2° J2/J3 offset arrived with S-V1.6-3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum DhVariant {
    /// `dh_is_offset = 1` (firmware S-V1.6-3 and later; the SDK default).
    #[default]
    Offset,
    /// `dh_is_offset = 0` (older firmware).
    Legacy,
}

/// A link frame's pose: position in mm, ZYX Euler angles (roll, pitch, yaw) in degrees
/// (R = Rz(yaw)·Ry(pitch)·Rx(roll)), as the SDK's `GetFK` reports it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LinkPose {
    /// X, mm.
    pub x_mm: f64,
    /// Y, mm.
    pub y_mm: f64,
    /// Z, mm.
    pub z_mm: f64,
    /// Roll (about X), degrees.
    pub roll_deg: f64,
    /// Pitch (about Y), degrees.
    pub pitch_deg: f64,
    /// Yaw (about Z), degrees.
    pub yaw_deg: f64,
}

/// (a mm, alpha rad, d mm) per joint.
const DH_A_ALPHA_D: [(f64, f64, f64); 6] = [
    (0.0, 0.0, 123.0),
    (0.0, -std::f64::consts::FRAC_PI_2, 0.0),
    (285.03, 0.0, 0.0),
    (-21.98, std::f64::consts::FRAC_PI_2, 250.75),
    (0.0, -std::f64::consts::FRAC_PI_2, 0.0),
    (0.0, std::f64::consts::FRAC_PI_2, 91.0),
];

fn theta_offsets_deg(variant: DhVariant) -> [f64; 6] {
    match variant {
        DhVariant::Offset => [0.0, -172.22, -102.78, 0.0, 0.0, 0.0],
        DhVariant::Legacy => [0.0, -174.22, -100.78, 0.0, 0.0, 0.0],
    }
}

/// The Piper's modified-DH table (metres, radians; no joint limits), which
/// [`forward_kinematics`] and the Arm API's solver both use.
pub fn dh_table(variant: DhVariant) -> [MdhJoint; 6] {
    let offsets = theta_offsets_deg(variant);
    std::array::from_fn(|i| {
        let (a_mm, alpha_rad, d_mm) = DH_A_ALPHA_D[i];
        MdhJoint::unlimited(
            a_mm / 1000.0,
            alpha_rad,
            d_mm / 1000.0,
            offsets[i].to_radians(),
        )
    })
}

/// A frame as the SDK reports it: mm and Z-Y-X Euler degrees.
fn link_pose(t: &Isometry3<f64>) -> LinkPose {
    let (roll, pitch, yaw) = t.rotation.euler_angles();
    let p = t.translation.vector * 1000.0;
    LinkPose {
        x_mm: p.x,
        y_mm: p.y,
        z_mm: p.z,
        roll_deg: roll.to_degrees(),
        pitch_deg: pitch.to_degrees(),
        yaw_deg: yaw.to_degrees(),
    }
}

/// Pose of each of the six link frames in the base frame for joint angles `q_rad`.
/// Element 5 is the flange (what 0x2A2–0x2A4 report).
///
/// ```
/// use driver::piper::{forward_kinematics, DhVariant};
/// let flange = forward_kinematics([0.0; 6], DhVariant::Offset)[5];
/// assert!((flange.x_mm - 56.128).abs() < 0.01 && (flange.pitch_deg - 85.0).abs() < 0.01);
/// ```
pub fn forward_kinematics(q_rad: [f64; 6], variant: DhVariant) -> [LinkPose; 6] {
    let frames = Chain::new(dh_table(variant).to_vec()).link_frames(&q_rad);
    std::array::from_fn(|i| link_pose(&frames[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn zero_pose_matches_the_firmware_values_of_both_variants() {
        // Spec §12: offset → (56.128, 0, 213.266) mm, legacy → (54.953, 0, 203.387) mm, both
        // with RPY (0°, 85°, 0°).
        for (variant, x, z) in [
            (DhVariant::Offset, 56.128, 213.266),
            (DhVariant::Legacy, 54.953, 203.387),
        ] {
            let flange = forward_kinematics([0.0; 6], variant)[5];
            assert!(close(flange.x_mm, x, 0.01), "{variant:?} {flange:?}");
            assert!(close(flange.y_mm, 0.0, 0.01), "{variant:?} {flange:?}");
            assert!(close(flange.z_mm, z, 0.01), "{variant:?} {flange:?}");
            assert!(close(flange.roll_deg, 0.0, 0.01), "{variant:?} {flange:?}");
            assert!(
                close(flange.pitch_deg, 85.0, 0.01),
                "{variant:?} {flange:?}"
            );
            assert!(close(flange.yaw_deg, 0.0, 0.01), "{variant:?} {flange:?}");
        }
    }

    #[test]
    fn base_rotation_turns_the_flange_about_z() {
        let q = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0];
        let flange = forward_kinematics(q, DhVariant::Offset)[5];
        assert!(
            close(flange.x_mm, 0.0, 0.01) && close(flange.y_mm, 56.128, 0.01),
            "{flange:?}"
        );
        let first = forward_kinematics(q, DhVariant::Offset)[0];
        assert!(
            close(first.z_mm, 123.0, 1e-9) && close(first.yaw_deg, 90.0, 1e-9),
            "{first:?}"
        );
    }
}
