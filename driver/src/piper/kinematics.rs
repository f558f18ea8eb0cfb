//! Forward kinematics of the Piper from the SDK's modified (Craig) DH table (spec §12),
//! implemented from the table, not from the SDK's code.

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

type Mat4 = [[f64; 4]; 4];

const IDENTITY: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

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

/// One row of the modified-DH table: a (mm), alpha (rad), d (mm) and the angle added to the
/// joint reading (rad).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DhRow {
    /// a(i-1), mm.
    pub a_mm: f64,
    /// alpha(i-1), rad.
    pub alpha_rad: f64,
    /// d(i), mm.
    pub d_mm: f64,
    /// θ offset, rad.
    pub theta_offset_rad: f64,
}

/// The DH table [`forward_kinematics`] uses, for other solvers (the Arm API's IK).
pub fn dh_table(variant: DhVariant) -> [DhRow; 6] {
    let offsets = theta_offsets_deg(variant);
    std::array::from_fn(|i| {
        let (a_mm, alpha_rad, d_mm) = DH_A_ALPHA_D[i];
        DhRow {
            a_mm,
            alpha_rad,
            d_mm,
            theta_offset_rad: offsets[i].to_radians(),
        }
    })
}

/// RotX(α)·TransX(a)·RotZ(θ)·TransZ(d).
fn link(a: f64, alpha: f64, theta: f64, d: f64) -> Mat4 {
    let (st, ct) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    [
        [ct, -st, 0.0, a],
        [st * ca, ct * ca, -sa, -sa * d],
        [st * sa, ct * sa, ca, ca * d],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn mul(x: &Mat4, y: &Mat4) -> Mat4 {
    let mut out = [[0.0; 4]; 4];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = (0..4).map(|k| x[i][k] * y[k][j]).sum();
        }
    }
    out
}

fn pose(t: &Mat4) -> LinkPose {
    let roll = t[2][1].atan2(t[2][2]);
    let pitch = (-t[2][0]).atan2((t[0][0] * t[0][0] + t[1][0] * t[1][0]).sqrt());
    let yaw = t[1][0].atan2(t[0][0]);
    LinkPose {
        x_mm: t[0][3],
        y_mm: t[1][3],
        z_mm: t[2][3],
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
    let offsets = theta_offsets_deg(variant);
    let mut t = IDENTITY;
    let mut out = [pose(&IDENTITY); 6];
    for i in 0..6 {
        let (a, alpha, d) = DH_A_ALPHA_D[i];
        t = mul(&t, &link(a, alpha, q_rad[i] + offsets[i].to_radians(), d));
        out[i] = pose(&t);
    }
    out
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
