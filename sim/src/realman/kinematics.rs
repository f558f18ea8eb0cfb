//! Forward and inverse kinematics of the flange (default tool, base frame) on the MDH model
//! of [`ArmModel`] (`docs/protocols/realman.md` §13).
//!
//! Poses are x, y, z in m and rx, ry, rz in rad with the controller's convention, intrinsic
//! Z-Y-X: `R = Rz(rz)·Ry(ry)·Rx(rx)` (§2).
//!
//! The inverse is numerical (Levenberg–Marquardt damped least squares on the geometric
//! Jacobian, joint limits enforced at every iteration, a bounded number of iterations and
//! restarts), so it serves the 6-joint RM65 and the redundant 7-joint RM75 alike.

use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3};

use super::model::ArmModel;
use crate::kinematics;

/// A flange (or any) pose: position in m, orientation as intrinsic Z-Y-X Euler angles in rad
/// (`R = Rz(rz)·Ry(ry)·Rx(rx)`; `euler_rad = [rx, ry, rz]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// x, y, z, m.
    pub position_m: [f64; 3],
    /// rx, ry, rz, rad.
    pub euler_rad: [f64; 3],
}

impl Pose {
    /// A pose from its position (m) and Euler angles (rad, `[rx, ry, rz]`).
    pub fn new(position_m: [f64; 3], euler_rad: [f64; 3]) -> Self {
        Self {
            position_m,
            euler_rad,
        }
    }

    /// The orientation as a unit quaternion `[w, x, y, z]` (the order of the wire's
    /// `pose_quat`), with `w ≥ 0`.
    pub fn quaternion_wxyz(&self) -> [f64; 4] {
        let q = self.rotation();
        let s = if q.w < 0.0 { -1.0 } else { 1.0 };
        [s * q.w, s * q.i, s * q.j, s * q.k]
    }

    /// A pose from a position (m) and a quaternion `[w, x, y, z]` (need not be normalised);
    /// `None` for a zero or non-finite quaternion.
    pub fn from_quaternion_wxyz(position_m: [f64; 3], wxyz: [f64; 4]) -> Option<Self> {
        if !wxyz.iter().chain(&position_m).all(|v| v.is_finite()) {
            return None;
        }
        let q = nalgebra::Quaternion::new(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
        let unit = UnitQuaternion::try_new(q, 1e-12)?;
        Some(Self::from_isometry(&Isometry3::from_parts(
            Translation3::from(Vector3::from(position_m)),
            unit,
        )))
    }

    /// The orientation as a unit quaternion.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        let [rx, ry, rz] = self.euler_rad;
        // nalgebra's (roll, pitch, yaw) is R = Rz(yaw)·Ry(pitch)·Rx(roll): our convention.
        UnitQuaternion::from_euler_angles(rx, ry, rz)
    }

    /// The pose as an isometry (m).
    pub fn to_isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.position_m)),
            self.rotation(),
        )
    }

    /// The pose of an isometry (m). Euler extraction: rx = atan2(R21, R22),
    /// ry = atan2(−R20, √(R00² + R10²)), rz = atan2(R10, R00); an angle that comes out as
    /// −π (within 1e-12) is reported as +π, as the vendor's SDK does at the zero pose.
    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        let [rx, ry, rz] = kinematics::zyx_euler_rad(&iso.rotation);
        let fold = |a: f64| {
            if a < -std::f64::consts::PI + 1e-12 {
                std::f64::consts::PI
            } else {
                a
            }
        };
        let t = iso.translation.vector;
        Self {
            position_m: [t.x, t.y, t.z],
            euler_rad: [fold(rx), ry, fold(rz)],
        }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.position_m
            .iter()
            .chain(&self.euler_rad)
            .all(|v| v.is_finite())
    }
}

/// Why [`inverse`] found no joint angles.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IkError {
    /// No joint angles reach the pose (out of the workspace, or the solver did not converge
    /// within its iteration budget).
    #[error("no inverse-kinematics solution for the pose")]
    NoSolution,
    /// The pose is reachable only with a joint beyond its limit.
    #[error("joint {joint} would need {value_deg:.3}°, beyond its limit {limit_deg:.3}°")]
    OutOfLimits {
        /// 0-based joint index.
        joint: usize,
        /// The angle the solution needs, °.
        value_deg: f64,
        /// The limit it exceeds, °.
        limit_deg: f64,
    },
    /// The seed has the wrong length or the target is not finite.
    #[error("bad input: {reason}")]
    BadInput {
        /// What is wrong.
        reason: String,
    },
}

/// The frame of every joint (frame i rotates about its own Z with joint i) followed by the
/// flange frame, in the base frame. `joints_rad` must have `model.dof` entries (missing ones
/// count as 0, extra ones are ignored).
pub fn joint_frames(model: &ArmModel, joints_rad: &[f64]) -> Vec<Isometry3<f64>> {
    let mut frames = Vec::with_capacity(model.dof + 1);
    frames.extend(kinematics::joint_frames_m(
        model.mdh.iter().copied(),
        joints_rad,
    ));
    let last = frames.last().copied().unwrap_or_else(Isometry3::identity);
    frames.push(last * Isometry3::translation(0.0, 0.0, model.flange_d_m));
    frames
}

/// The flange frame in the base frame as an isometry (m).
pub fn forward_isometry(model: &ArmModel, joints_rad: &[f64]) -> Isometry3<f64> {
    joint_frames(model, joints_rad)
        .pop()
        .unwrap_or_else(Isometry3::identity)
}

/// The flange pose (default tool, base work frame) at `joints_rad` (rad, `model.dof` entries).
pub fn forward(model: &ArmModel, joints_rad: &[f64]) -> Pose {
    Pose::from_isometry(&forward_isometry(model, joints_rad))
}

/// The geometric Jacobian of the flange (6 × dof: linear velocity over angular velocity, base
/// frame) at `joints_rad`.
pub fn jacobian(model: &ArmModel, joints_rad: &[f64]) -> DMatrix<f64> {
    let frames = joint_frames(model, joints_rad);
    let tip = frames[model.dof].translation.vector;
    let mut j = DMatrix::zeros(6, model.dof);
    for (i, f) in frames[..model.dof].iter().enumerate() {
        let (lin, z) = kinematics::jacobian_column(f, &tip);
        for k in 0..3 {
            j[(k, i)] = lin[k];
            j[(k + 3, i)] = z[k];
        }
    }
    j
}

/// Position error weight, 1/m: 0.5 m of position error counts like 1 rad of orientation error.
const POSITION_WEIGHT_PER_M: f64 = 2.0;
/// Converged when the position error is below this, m (1e-5 mm).
const TOL_POSITION_M: f64 = 1e-8;
/// Converged when the orientation error is below this, rad.
const TOL_ROTATION_RAD: f64 = 1e-8;
/// Iterations per attempt.
const MAX_ITERATIONS: usize = 80;
/// Largest joint change in one iteration, rad.
const MAX_STEP_RAD: f64 = 0.4;

/// Weighted 6-vector error (position then rotation, base frame) from `current` to `target`.
fn pose_error(target: &Isometry3<f64>, current: &Isometry3<f64>) -> (DVector<f64>, f64, f64) {
    let (dp, dr) = kinematics::pose_error(target, current);
    let e = DVector::from_vec(vec![
        dp.x * POSITION_WEIGHT_PER_M,
        dp.y * POSITION_WEIGHT_PER_M,
        dp.z * POSITION_WEIGHT_PER_M,
        dr.x,
        dr.y,
        dr.z,
    ]);
    (e, dp.norm(), dr.norm())
}

/// Bring joint values into `[lo, hi]`: first by whole turns, then by clamping.
fn project(q: &mut [f64], lo: &[f64], hi: &[f64]) {
    use std::f64::consts::TAU;
    for ((v, &l), &h) in q.iter_mut().zip(lo).zip(hi) {
        if *v < l && *v + TAU <= h {
            *v += TAU * ((l - *v) / TAU).ceil();
        } else if *v > h && *v - TAU >= l {
            *v -= TAU * ((*v - h) / TAU).ceil();
        }
        *v = v.clamp(l, h);
    }
}

/// Statistics of the last IK solve (for benchmarks and reports).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IkStats {
    /// Iterations over all attempts.
    pub iterations: usize,
    /// Attempts (restarts + 1).
    pub attempts: usize,
}

/// One Levenberg–Marquardt run from `seed`; `Some(q)` when it converged. With `limits`, every
/// iterate is projected into them.
fn solve_from(
    model: &ArmModel,
    target: &Isometry3<f64>,
    seed: &[f64],
    limits: Option<(&[f64], &[f64])>,
    stats: &mut IkStats,
) -> Option<Vec<f64>> {
    let mut q = seed.to_vec();
    if let Some((lo, hi)) = limits {
        project(&mut q, lo, hi);
    }
    let (mut e, mut ep, mut er) = pose_error(target, &forward_isometry(model, &q));
    let mut lambda = 1e-3;
    for _ in 0..MAX_ITERATIONS {
        if ep < TOL_POSITION_M && er < TOL_ROTATION_RAD {
            return Some(q);
        }
        stats.iterations += 1;
        let mut jac = jacobian(model, &q);
        for r in 0..3 {
            for c in 0..model.dof {
                jac[(r, c)] *= POSITION_WEIGHT_PER_M;
            }
        }
        let jjt = &jac * jac.transpose() + DMatrix::identity(6, 6) * (lambda * lambda);
        let Some(y) = jjt.cholesky().map(|c| c.solve(&e)) else {
            lambda *= 10.0;
            continue;
        };
        let mut dq = jac.transpose() * y;
        let largest = dq.amax();
        if largest > MAX_STEP_RAD {
            dq *= MAX_STEP_RAD / largest;
        }
        let mut trial: Vec<f64> = q.iter().zip(dq.iter()).map(|(a, d)| a + d).collect();
        if let Some((lo, hi)) = limits {
            project(&mut trial, lo, hi);
        }
        let (te, tp, tr) = pose_error(target, &forward_isometry(model, &trial));
        if te.norm() < e.norm() {
            (q, e, ep, er) = (trial, te, tp, tr);
            lambda = (lambda * 0.3).max(1e-9);
        } else {
            lambda = (lambda * 8.0).min(10.0);
        }
    }
    (ep < TOL_POSITION_M && er < TOL_ROTATION_RAD).then_some(q)
}

/// Restart seeds after the caller's: the seed with the wrist flipped, then a few spread
/// configurations (deterministic, so the emulator is reproducible).
fn restart_seeds(model: &ArmModel, seed: &[f64]) -> Vec<Vec<f64>> {
    use std::f64::consts::FRAC_PI_2;
    let n = model.dof;
    let mut seeds = Vec::new();
    let mut flipped = seed.to_vec();
    if n >= 3 {
        flipped[n - 2] = -flipped[n - 2];
        flipped[n - 3] += std::f64::consts::PI;
        flipped[n - 1] += std::f64::consts::PI;
    }
    seeds.push(flipped);
    let spread: [[f64; 3]; 6] = [
        [0.0, 0.5, 1.0],
        [0.0, -0.5, -1.0],
        [FRAC_PI_2, 0.8, 0.8],
        [-FRAC_PI_2, -0.8, -0.8],
        [3.0, 0.3, 1.5],
        [-3.0, -0.3, -1.5],
    ];
    for s in spread {
        seeds.push(
            (0..n)
                .map(|i| match i {
                    0 => seed.first().copied().unwrap_or(0.0) + s[0] * 0.5,
                    _ => s[1 + i % 2] * if i % 3 == 0 { -1.0 } else { 1.0 },
                })
                .collect(),
        );
    }
    seeds
}

/// Joint angles (rad) that put the flange at `target`, close to `seed_rad` when possible.
///
/// Tries the seed first, then a fixed set of restarts (at most 8 attempts of 80 iterations).
/// Errors: [`IkError::NoSolution`] when the pose is out of reach or no attempt converged;
/// [`IkError::OutOfLimits`] when the pose is reachable only beyond a joint limit.
pub fn inverse(model: &ArmModel, target: &Pose, seed_rad: &[f64]) -> Result<Vec<f64>, IkError> {
    inverse_with_stats(model, target, seed_rad).0
}

/// [`inverse`], also returning how many iterations and attempts it took.
pub fn inverse_with_stats(
    model: &ArmModel,
    target: &Pose,
    seed_rad: &[f64],
) -> (Result<Vec<f64>, IkError>, IkStats) {
    let mut stats = IkStats::default();
    if seed_rad.len() != model.dof || seed_rad.iter().any(|v| !v.is_finite()) {
        let reason = format!("seed needs {} finite angles", model.dof);
        return (Err(IkError::BadInput { reason }), stats);
    }
    if !target.is_finite() {
        let reason = "target pose is not finite".to_owned();
        return (Err(IkError::BadInput { reason }), stats);
    }
    let goal = target.to_isometry();
    let shoulder = Vector3::new(0.0, 0.0, model.shoulder_height_m());
    if (goal.translation.vector - shoulder).norm() > model.reach_m() + 1e-6 {
        return (Err(IkError::NoSolution), stats);
    }
    let (lo, hi) = (model.joint_min_rad(), model.joint_max_rad());
    let mut seeds = vec![seed_rad.to_vec()];
    seeds.extend(restart_seeds(model, seed_rad));
    for seed in &seeds {
        stats.attempts += 1;
        if let Some(q) = solve_from(model, &goal, seed, Some((&lo, &hi)), &mut stats) {
            return (Ok(q), stats);
        }
    }
    // Tell "beyond a limit" from "unreachable": solve once without limits.
    stats.attempts += 1;
    let Some(mut q) = solve_from(model, &goal, seed_rad, None, &mut stats) else {
        return (Err(IkError::NoSolution), stats);
    };
    for v in q.iter_mut() {
        *v = (*v + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    }
    let err = match model.first_out_of_limits(&q) {
        Some(j) => {
            let value_deg = q[j].to_degrees();
            let limit_deg = if value_deg < 0.0 {
                model.joint_min_deg[j]
            } else {
                model.joint_max_deg[j]
            };
            IkError::OutOfLimits {
                joint: j,
                value_deg,
                limit_deg,
            }
        }
        // Converged within limits only without projection: count it as found.
        None => return (Ok(q), stats),
    };
    (Err(err), stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternion_round_trip() {
        let p = Pose::new([0.1, -0.2, 0.3], [0.4, -0.5, 2.5]);
        let q = p.quaternion_wxyz();
        let back = Pose::from_quaternion_wxyz(p.position_m, q).expect("unit");
        for k in 0..3 {
            assert!((back.euler_rad[k] - p.euler_rad[k]).abs() < 1e-12);
        }
        assert!(Pose::from_quaternion_wxyz([0.0; 3], [0.0; 4]).is_none());
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let m = ArmModel::rm65b();
        let q = [0.1, 0.4, -0.7, 0.3, 0.9, -0.2];
        let j = jacobian(&m, &q);
        let h = 1e-7;
        for c in 0..6 {
            let mut qp = q;
            qp[c] += h;
            let a = forward_isometry(&m, &q);
            let b = forward_isometry(&m, &qp);
            let dp = (b.translation.vector - a.translation.vector) / h;
            let dr = (b.rotation * a.rotation.inverse()).scaled_axis() / h;
            for k in 0..3 {
                assert!((j[(k, c)] - dp[k]).abs() < 1e-5);
                assert!((j[(k + 3, c)] - dr[k]).abs() < 1e-5);
            }
        }
    }
}
