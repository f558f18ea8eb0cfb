//! Piper kinematics as the firmware computes it (protocol spec §12): modified (Craig) DH
//! forward kinematics of the link-6 flange, in both DH variants, a damped-least-squares
//! inverse kinematics for MOVE P / MOVE L, and Cartesian interpolation helpers.
//!
//! Units: joint angles in rad; flange position in mm (the firmware's unit, reported in
//! 0x2A2–0x2A4 as 0.001 mm); orientation as RX, RY, RZ in rad with
//! `R = Rz(RZ)·Ry(RY)·Rx(RX)` (spec §3, the convention of 0x2A2–0x2A4 and of the SDK FK).
//! Frames returned as isometries are in metres.
//!
//! `urdf/piper.urdf` is built on the same DH frames as [`DhVariant::Offset`]: its joint angles
//! are the firmware's q and its `link6` frame is the flange, so the physics world and this FK
//! agree by construction (a test checks it).

use nalgebra::{
    Isometry3, Matrix6, Point3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6,
};

use crate::kinematics::{jacobian_column, joint_frames_m, pose_error, zyx_euler_rad, MdhRow};

/// The Piper URDF (authored by the project, see `urdf/README.md`), for
/// [`crate::physics::RapierWorld::from_urdf_str`].
pub const PIPER_URDF: &str = include_str!("../../../urdf/piper.urdf");

/// Number of arm joints.
pub const JOINTS: usize = 6;

/// Which DH table the firmware uses (spec §12, `dh_is_offset` in the SDK).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DhVariant {
    /// Firmware ≥ S-V1.6-3 (`dh_is_offset = 1`, SDK default): J2 offset −172.22°, J3 −102.78°.
    Offset,
    /// Firmware < S-V1.6-3 (`dh_is_offset = 0`): J2 offset −174.22°, J3 −100.78°.
    NoOffset,
}

impl DhVariant {
    /// The variant for a firmware whose FK does (`true`) or does not use the 2° offsets.
    pub fn from_offset_flag(dh_is_offset: bool) -> Self {
        if dh_is_offset {
            Self::Offset
        } else {
            Self::NoOffset
        }
    }

    /// The modified-DH table of this variant (spec §12: a and d in mm there, twists exactly
    /// ±π/2).
    pub fn table(self) -> [MdhRow; JOINTS] {
        let (theta2_deg, theta3_deg): (f64, f64) = match self {
            Self::Offset => (-172.22, -102.78),
            Self::NoOffset => (-174.22, -100.78),
        };
        let half_pi = std::f64::consts::FRAC_PI_2;
        let row = |a_mm: f64, alpha_rad, offset_rad, d_mm: f64| {
            MdhRow::new(a_mm / 1000.0, alpha_rad, d_mm / 1000.0, offset_rad)
        };
        [
            row(0.0, 0.0, 0.0, 123.0),
            row(0.0, -half_pi, theta2_deg.to_radians(), 0.0),
            row(285.03, 0.0, theta3_deg.to_radians(), 0.0),
            row(-21.98, half_pi, 0.0, 250.75),
            row(0.0, -half_pi, 0.0, 0.0),
            row(0.0, half_pi, 0.0, 91.0),
        ]
    }
}

/// Pose of the link-6 flange in `base_link` (no TCP offset), as reported in 0x2A2–0x2A4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlangePose {
    /// X, mm.
    pub x_mm: f64,
    /// Y, mm.
    pub y_mm: f64,
    /// Z, mm.
    pub z_mm: f64,
    /// RX (roll about fixed X, applied first), rad.
    pub rx_rad: f64,
    /// RY (pitch about fixed Y), rad.
    pub ry_rad: f64,
    /// RZ (yaw about fixed Z, applied last), rad.
    pub rz_rad: f64,
}

impl FlangePose {
    /// The pose as an isometry in metres; rotation `Rz(RZ)·Ry(RY)·Rx(RX)`.
    pub fn to_isometry_m(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.x_mm / 1000.0, self.y_mm / 1000.0, self.z_mm / 1000.0),
            UnitQuaternion::from_euler_angles(self.rx_rad, self.ry_rad, self.rz_rad),
        )
    }

    /// The pose of an isometry in metres, with the SDK's Euler extraction:
    /// RX = atan2(R21, R22), RY = atan2(−R20, √(R00² + R10²)), RZ = atan2(R10, R00).
    pub fn from_isometry_m(pose: &Isometry3<f64>) -> Self {
        let [rx_rad, ry_rad, rz_rad] = zyx_euler_rad(&pose.rotation);
        let t = pose.translation.vector * 1000.0;
        Self {
            x_mm: t.x,
            y_mm: t.y,
            z_mm: t.z,
            rx_rad,
            ry_rad,
            rz_rad,
        }
    }

    /// RX, RY, RZ in degrees (the wire reports 0.001°).
    pub fn angles_deg(&self) -> [f64; 3] {
        [
            self.rx_rad.to_degrees(),
            self.ry_rad.to_degrees(),
            self.rz_rad.to_degrees(),
        ]
    }

    /// Whether every field is finite.
    pub fn is_finite(&self) -> bool {
        [
            self.x_mm,
            self.y_mm,
            self.z_mm,
            self.rx_rad,
            self.ry_rad,
            self.rz_rad,
        ]
        .iter()
        .all(|v| v.is_finite())
    }
}

/// The six link frames (frame i moves with joint i) in `base_link`, in metres.
pub fn link_frames_m(variant: DhVariant, q_rad: &[f64; JOINTS]) -> [Isometry3<f64>; JOINTS] {
    let table = variant.table();
    let mut frames = [Isometry3::identity(); JOINTS];
    for (frame, chained) in frames.iter_mut().zip(joint_frames_m(table, q_rad)) {
        *frame = chained;
    }
    frames
}

/// Flange pose at joint angles `q_rad`, as the firmware of `variant` reports it.
pub fn forward(variant: DhVariant, q_rad: &[f64; JOINTS]) -> FlangePose {
    FlangePose::from_isometry_m(&link_frames_m(variant, q_rad)[JOINTS - 1])
}

/// Joint limits used by the IK, rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Lower limits, rad.
    pub lower_rad: [f64; JOINTS],
    /// Upper limits, rad.
    pub upper_rad: [f64; JOINTS],
}

impl JointLimits {
    /// The firmware's default limits as reported in 0x473 (spec §9.1, `[OBS]` column, 0.1°):
    /// J1 ±150°, J2 0…180°, J3 −170…0°, J4 ±89°, J5 ±89°, J6 ±180°. `urdf/piper.urdf` uses
    /// the same values.
    pub fn firmware_default() -> Self {
        let deg = |v: f64| v.to_radians();
        Self {
            lower_rad: [
                deg(-150.0),
                0.0,
                deg(-170.0),
                deg(-89.0),
                deg(-89.0),
                deg(-180.0),
            ],
            upper_rad: [
                deg(150.0),
                deg(180.0),
                0.0,
                deg(89.0),
                deg(89.0),
                deg(180.0),
            ],
        }
    }

    /// Whether every angle of `q_rad` lies within the limits.
    pub fn contains(&self, q_rad: &[f64; JOINTS]) -> bool {
        (0..JOINTS).all(|i| q_rad[i] >= self.lower_rad[i] && q_rad[i] <= self.upper_rad[i])
    }

    fn clamp(&self, q_rad: &mut [f64; JOINTS]) {
        for (i, q) in q_rad.iter_mut().enumerate() {
            *q = q.clamp(self.lower_rad[i], self.upper_rad[i]);
        }
    }
}

/// Tuning of [`inverse`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkOptions {
    /// Accept a solution whose flange position is within this distance of the target, mm.
    pub position_tolerance_mm: f64,
    /// Accept a solution whose flange orientation is within this angle of the target, rad.
    pub orientation_tolerance_rad: f64,
    /// Iterations per start.
    pub max_iterations: usize,
    /// Length that weighs one radian of orientation error against position error, m.
    pub orientation_weight_m: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            // The wire resolution is 0.001 mm and 0.001° (1.7e-5 rad): stay below it.
            position_tolerance_mm: 0.001,
            orientation_tolerance_rad: 1e-5,
            max_iterations: 200,
            orientation_weight_m: 0.1,
        }
    }
}

/// Why [`inverse`] found no joint angles.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IkError {
    /// The target has a NaN or infinite field.
    #[error("IK target is not finite: {target:?}")]
    InvalidTarget {
        /// The rejected target.
        target: FlangePose,
    },
    /// No joint angles within the limits reach the target (out of reach, or only reachable
    /// past a joint limit). The residual is that of the best attempt.
    #[error("no IK solution: best attempt misses by {position_error_mm:.3} mm, {orientation_error_rad:.5} rad")]
    NoSolution {
        /// Position error of the best attempt, mm.
        position_error_mm: f64,
        /// Orientation error of the best attempt, rad.
        orientation_error_rad: f64,
    },
}

/// Geometric Jacobian of the flange (rows: linear m/rad, then angular), world frame.
fn jacobian(frames: &[Isometry3<f64>; JOINTS]) -> Matrix6<f64> {
    let flange = frames[JOINTS - 1].translation.vector;
    let mut j = Matrix6::zeros();
    for (i, f) in frames.iter().enumerate() {
        let (lin, z) = jacobian_column(f, &flange);
        j.fixed_view_mut::<3, 1>(0, i).copy_from(&lin);
        j.fixed_view_mut::<3, 1>(3, i).copy_from(&z);
    }
    j
}

struct Attempt {
    q: [f64; JOINTS],
    position_error_mm: f64,
    orientation_error_rad: f64,
}

/// Damped least squares from one start, with the step projected onto the joint limits.
fn solve_from(
    variant: DhVariant,
    target: &Isometry3<f64>,
    start: [f64; JOINTS],
    limits: &JointLimits,
    options: &IkOptions,
) -> Attempt {
    let w = options.orientation_weight_m;
    let weighted = |dp: Vector3<f64>, dr: Vector3<f64>| {
        Vector6::new(dp.x, dp.y, dp.z, w * dr.x, w * dr.y, w * dr.z)
    };
    let mut q = start;
    limits.clamp(&mut q);
    let mut frames = link_frames_m(variant, &q);
    let (mut dp, mut dr) = pose_error(target, &frames[JOINTS - 1]);
    let mut cost = weighted(dp, dr).norm_squared();
    // Levenberg–Marquardt style damping: shrink after a good step, grow after a bad one.
    let mut lambda = 1e-2;
    for _ in 0..options.max_iterations {
        if dp.norm() * 1000.0 <= options.position_tolerance_mm
            && dr.norm() <= options.orientation_tolerance_rad
        {
            break;
        }
        let mut jac = jacobian(&frames);
        for r in 3..6 {
            for c in 0..JOINTS {
                jac[(r, c)] *= w;
            }
        }
        let e = weighted(dp, dr);
        let jjt = jac * jac.transpose() + Matrix6::identity() * (lambda * lambda);
        let Some(x) = jjt.cholesky().map(|c| c.solve(&e)) else {
            lambda *= 4.0;
            continue;
        };
        let step = jac.transpose() * x;
        let mut candidate = q;
        for (i, c) in candidate.iter_mut().enumerate() {
            *c += step[i];
        }
        limits.clamp(&mut candidate);
        let candidate_frames = link_frames_m(variant, &candidate);
        let (cdp, cdr) = pose_error(target, &candidate_frames[JOINTS - 1]);
        let candidate_cost = weighted(cdp, cdr).norm_squared();
        if candidate_cost < cost {
            q = candidate;
            frames = candidate_frames;
            (dp, dr, cost) = (cdp, cdr, candidate_cost);
            lambda = (lambda * 0.3).max(1e-6);
        } else {
            lambda *= 4.0;
            if lambda > 1e3 {
                break; // stuck against a limit or at a local minimum
            }
        }
    }
    Attempt {
        q,
        position_error_mm: dp.norm() * 1000.0,
        orientation_error_rad: dr.norm(),
    }
}

/// Joint angles (rad) that put the flange at `target`, found by damped least squares from
/// `seed_rad` (normally the current joint angles, so the arm stays on its branch), within
/// `limits`.
///
/// If the seed does not converge, a few fixed starts are tried (deterministic); the solution
/// closest to the seed wins. Unreachable targets, or targets only reachable past a limit,
/// give [`IkError::NoSolution`].
pub fn inverse(
    variant: DhVariant,
    target: &FlangePose,
    seed_rad: &[f64; JOINTS],
    limits: &JointLimits,
    options: &IkOptions,
) -> Result<[f64; JOINTS], IkError> {
    if !target.is_finite() || seed_rad.iter().any(|v| !v.is_finite()) {
        return Err(IkError::InvalidTarget { target: *target });
    }
    let goal = target.to_isometry_m();
    let mid: [f64; JOINTS] =
        std::array::from_fn(|i| 0.5 * (limits.lower_rad[i] + limits.upper_rad[i]));
    // Extra starts: the range middle and a few elbow / wrist configurations, with J1 aimed at
    // the target so the shoulder starts on the right side.
    let yaw = goal.translation.y.atan2(goal.translation.x);
    let starts = [
        *seed_rad,
        mid,
        [yaw, 1.2, -1.2, 0.0, 0.5, 0.0],
        [yaw, 0.6, -0.6, 0.0, -0.5, 0.0],
        [yaw, 2.0, -2.0, 0.5, 0.0, 0.0],
        [yaw, 1.0, -2.2, -0.5, 0.8, 0.0],
    ];
    let mut best: Option<Attempt> = None;
    let converged = |a: &Attempt| {
        a.position_error_mm <= options.position_tolerance_mm
            && a.orientation_error_rad <= options.orientation_tolerance_rad
    };
    for start in starts {
        let attempt = solve_from(variant, &goal, start, limits, options);
        if converged(&attempt) {
            return Ok(attempt.q);
        }
        let score = |a: &Attempt| {
            a.position_error_mm / 1000.0 + options.orientation_weight_m * a.orientation_error_rad
        };
        if best.as_ref().is_none_or(|b| score(&attempt) < score(b)) {
            best = Some(attempt);
        }
    }
    let best = best.map_or((f64::INFINITY, f64::INFINITY), |b| {
        (b.position_error_mm, b.orientation_error_rad)
    });
    Err(IkError::NoSolution {
        position_error_mm: best.0,
        orientation_error_rad: best.1,
    })
}

/// The pose a fraction `s` (0 → `from`, 1 → `to`) along the straight line between two flange
/// poses: linear in position, spherical-linear (shortest arc) in orientation. For MOVE L.
pub fn interpolate(from: &FlangePose, to: &FlangePose, s: f64) -> FlangePose {
    let a = from.to_isometry_m();
    let b = to.to_isometry_m();
    let p = a.translation.vector.lerp(&b.translation.vector, s);
    let r = a.rotation.slerp(&b.rotation, s);
    FlangePose::from_isometry_m(&Isometry3::from_parts(Translation3::from(p), r))
}

/// Straight-line distance between two flange positions, mm, and the angle between their
/// orientations, rad. Useful to size a MOVE L by the end-effector speed limits.
pub fn pose_distance(from: &FlangePose, to: &FlangePose) -> (f64, f64) {
    let a = from.to_isometry_m();
    let b = to.to_isometry_m();
    let dp = Point3::from(a.translation.vector) - Point3::from(b.translation.vector);
    let angle = a.rotation.angle_to(&b.rotation);
    (dp.norm() * 1000.0, angle)
}

/// The rotation matrix of a flange pose (`Rz(RZ)·Ry(RY)·Rx(RX)`).
pub fn rotation_of(pose: &FlangePose) -> Rotation3<f64> {
    Rotation3::from_euler_angles(pose.rx_rad, pose.ry_rad, pose.rz_rad)
}

#[cfg(test)]
mod tests;
