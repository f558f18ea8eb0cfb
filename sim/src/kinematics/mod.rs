//! Modified (Craig) DH kinematics shared by the arm emulators: the row type of an MDH table,
//! the frames of a chain, the columns of its geometric Jacobian, the pose error an
//! inverse-kinematics iteration reduces, and the Z-Y-X Euler angles both controllers report.
//!
//! Each arm keeps its own table (`piper::kinematics::DhVariant::table`,
//! `realman::model::ArmModel::mdh`), its own pose type in its own units and its own IK
//! solver: the two firmwares' solvers differ in tuning (damping schedule, step bound,
//! tolerances, restarts) and in what they report when they fail, and each emulator must keep
//! answering exactly as before.
//!
//! Units: lengths in m, angles in rad.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};

#[cfg(test)]
mod tests;

/// One row of a modified-DH table: frame i follows frame i−1 by
/// `RotX(α_{i−1})·TransX(a_{i−1})·RotZ(q_i + offset_i)·TransZ(d_i)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MdhRow {
    /// Link length a(i−1), m.
    pub a_m: f64,
    /// Link twist α(i−1), rad.
    pub alpha_rad: f64,
    /// Link offset d(i), m.
    pub d_m: f64,
    /// Offset added to the joint reading to get the model angle, rad.
    pub offset_rad: f64,
}

impl MdhRow {
    /// A row from its values in m and rad.
    pub const fn new(a_m: f64, alpha_rad: f64, d_m: f64, offset_rad: f64) -> Self {
        Self {
            a_m,
            alpha_rad,
            d_m,
            offset_rad,
        }
    }

    /// A row from a table's usual units: a mm, α °, d mm, offset °.
    pub fn from_mm_deg(a_mm: f64, alpha_deg: f64, d_mm: f64, offset_deg: f64) -> Self {
        Self::new(
            a_mm / 1000.0,
            alpha_deg.to_radians(),
            d_mm / 1000.0,
            offset_deg.to_radians(),
        )
    }

    /// The transform from frame i−1 to frame i at joint reading `q_rad`, m.
    pub fn transform_m(&self, q_rad: f64) -> Isometry3<f64> {
        let twist = Isometry3::rotation(Vector3::x() * self.alpha_rad);
        let length = Isometry3::translation(self.a_m, 0.0, 0.0);
        let turn = Isometry3::rotation(Vector3::z() * (self.offset_rad + q_rad));
        let offset = Isometry3::translation(0.0, 0.0, self.d_m);
        twist * length * turn * offset
    }
}

/// The frame of every joint of the chain `rows` (base first) in its base frame, m (frame i
/// turns about its own z with joint i). `joints_rad` holds one reading per row; a missing one
/// counts as 0.
pub fn joint_frames_m<'a>(
    rows: impl IntoIterator<Item = MdhRow> + 'a,
    joints_rad: &'a [f64],
) -> impl Iterator<Item = Isometry3<f64>> + 'a {
    rows.into_iter()
        .enumerate()
        .scan(Isometry3::identity(), move |acc, (i, row)| {
            let q_rad = joints_rad.get(i).copied().unwrap_or(0.0);
            *acc *= row.transform_m(q_rad);
            Some(*acc)
        })
}

/// The Jacobian column of a revolute joint whose frame is `joint_frame` for a point `tip_m`
/// (both in the base frame): the point's linear velocity per rad/s (m/s) and the angular
/// velocity (rad/s), as `(linear, angular)`.
pub fn jacobian_column(
    joint_frame: &Isometry3<f64>,
    tip_m: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    // Modified DH: joint i turns about z of frame i, through the frame's origin.
    let axis = joint_frame.rotation * Vector3::z();
    let linear = axis.cross(&(tip_m - joint_frame.translation.vector));
    (linear, axis)
}

/// The error from `current` to `target`, in the base frame: position (m) and rotation as a
/// scaled axis (rad), the quantities an IK iteration drives to zero.
pub fn pose_error(
    target: &Isometry3<f64>,
    current: &Isometry3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let position_m = target.translation.vector - current.translation.vector;
    let rotation_rad = (target.rotation * current.rotation.inverse()).scaled_axis();
    (position_m, rotation_rad)
}

/// The Euler angles `[rx, ry, rz]` (rad) of `rotation = Rz(rz)·Ry(ry)·Rx(rx)` as both
/// controllers extract them: rx = atan2(R21, R22), ry = atan2(−R20, √(R00² + R10²)),
/// rz = atan2(R10, R00).
pub fn zyx_euler_rad(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let r = rotation.to_rotation_matrix();
    let m = r.matrix();
    [
        m[(2, 1)].atan2(m[(2, 2)]),
        (-m[(2, 0)]).atan2(m[(0, 0)].hypot(m[(1, 0)])),
        m[(1, 0)].atan2(m[(0, 0)]),
    ]
}
