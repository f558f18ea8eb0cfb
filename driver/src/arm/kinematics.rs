//! Flange kinematics on a modified (Craig) DH chain, shared by the backends: forward
//! kinematics in closed form, inverse kinematics by damped least squares (Levenberg–Marquardt
//! on the 6-D pose error with a finite-difference Jacobian), kept inside the joint limits.

use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3};

use super::error::{AbcErrorCode, ArmError};
use super::types::{IkMode, Pose};

/// One joint of a modified-DH chain: the transform to its frame is
/// RotX(alpha)·TransX(a)·RotZ(q + offset)·TransZ(d).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MdhJoint {
    /// a(i-1), metres.
    pub a_m: f64,
    /// alpha(i-1), radians.
    pub alpha_rad: f64,
    /// d(i), metres.
    pub d_m: f64,
    /// Added to the joint reading, radians.
    pub offset_rad: f64,
    /// Lower joint limit, radians.
    pub min_rad: f64,
    /// Upper joint limit, radians.
    pub max_rad: f64,
}

impl MdhJoint {
    /// A joint of this geometry without limits (the chain's user clamps, or does not).
    pub fn unlimited(a_m: f64, alpha_rad: f64, d_m: f64, offset_rad: f64) -> Self {
        Self {
            a_m,
            alpha_rad,
            d_m,
            offset_rad,
            min_rad: f64::NEG_INFINITY,
            max_rad: f64::INFINITY,
        }
    }

    /// The transform from the previous frame to this joint's at reading `q_rad`.
    fn transform(&self, q_rad: f64) -> Isometry3<f64> {
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), self.alpha_rad);
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q_rad + self.offset_rad);
        Isometry3::from_parts(Translation3::identity(), rx)
            * Isometry3::translation(self.a_m, 0.0, 0.0)
            * Isometry3::from_parts(Translation3::identity(), rz)
            * Isometry3::translation(0.0, 0.0, self.d_m)
    }
}

/// A serial chain from the base to the flange, with an optional reference frame in front
/// (poses are reported in it) and a tool behind (poses are of the tool point).
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    joints: Vec<MdhJoint>,
    /// Reference frame ← base.
    base: Isometry3<f64>,
    /// Flange → tool.
    tool: Isometry3<f64>,
}

/// Solver tolerances: what counts as "at the pose".
const POS_TOL_M: f64 = 1e-6;
const ROT_TOL_RAD: f64 = 1e-6;
const MAX_ITERATIONS: usize = 200;
/// Extra starting points of the iterative search.
const SEARCH_STARTS: usize = 24;

impl Chain {
    /// A chain of `joints`, base first; poses of the flange in the base frame.
    pub fn new(joints: Vec<MdhJoint>) -> Self {
        Self {
            joints,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
        }
    }

    /// Poses of the point `tool` (a pose in the flange frame) expressed in the frame `work`
    /// (its pose in the base frame).
    pub fn with_frames(mut self, work: &Pose, tool: &Pose) -> Self {
        self.base = to_isometry(work).inverse();
        self.tool = to_isometry(tool);
        self
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The joints.
    pub fn joints(&self) -> &[MdhJoint] {
        &self.joints
    }

    fn transform(&self, q_rad: &[f64]) -> Isometry3<f64> {
        let mut t = self.base;
        for (j, q) in self.joints.iter().zip(q_rad) {
            t *= j.transform(*q);
        }
        t * self.tool
    }

    /// Every joint's frame in the reference frame for joint angles `q_rad`, base first; the
    /// last is the flange's (without the tool).
    pub fn link_frames(&self, q_rad: &[f64]) -> Vec<Isometry3<f64>> {
        let mut t = self.base;
        self.joints
            .iter()
            .zip(q_rad)
            .map(|(j, q)| {
                t *= j.transform(*q);
                t
            })
            .collect()
    }

    /// Flange pose for joint angles `q_rad` (one per joint).
    pub fn forward(&self, q_rad: &[f64]) -> Pose {
        to_pose(&self.transform(q_rad))
    }

    /// Whether every angle is inside its joint's limits (with a small tolerance).
    pub fn within_limits(&self, q_rad: &[f64]) -> bool {
        self.joints
            .iter()
            .zip(q_rad)
            .all(|(j, q)| *q >= j.min_rad - 1e-9 && *q <= j.max_rad + 1e-9)
    }

    /// Joint angles that put the flange at `target`, or `None` when the solver finds none
    /// within the limits. `seed_rad` is the reference configuration (the solution nearest to
    /// it is what single-step mode finds); the iterative search adds fixed starting points.
    pub fn inverse(&self, target: &Pose, seed_rad: &[f64], mode: IkMode) -> Option<Vec<f64>> {
        let goal = to_isometry(target);
        let seed: Vec<f64> = self
            .joints
            .iter()
            .zip(seed_rad.iter().chain(std::iter::repeat(&0.0)))
            .map(|(j, q)| q.clamp(j.min_rad, j.max_rad))
            .collect();
        if let Some(q) = self.solve(&goal, seed) {
            return Some(q);
        }
        if mode == IkMode::SingleStep {
            return None;
        }
        let mut rng = 0x9E37_79B9_7F4A_7C15u64;
        (0..SEARCH_STARTS).find_map(|_| {
            let start = self
                .joints
                .iter()
                .map(|j| j.min_rad + (j.max_rad - j.min_rad) * next_unit(&mut rng))
                .collect();
            self.solve(&goal, start)
        })
    }

    fn error(&self, q: &[f64], goal: &Isometry3<f64>) -> DVector<f64> {
        let t = self.transform(q);
        let dp = goal.translation.vector - t.translation.vector;
        let dr = (goal.rotation * t.rotation.inverse()).scaled_axis();
        DVector::from_iterator(6, dp.iter().chain(dr.iter()).copied())
    }

    fn solve(&self, goal: &Isometry3<f64>, mut q: Vec<f64>) -> Option<Vec<f64>> {
        let n = self.dof();
        let mut lambda = 1e-3;
        let mut e = self.error(&q, goal);
        for _ in 0..MAX_ITERATIONS {
            if converged(&e) {
                return Some(q);
            }
            let jac = self.jacobian(&q, goal, &e);
            let jjt = &jac * jac.transpose() + DMatrix::identity(6, 6) * (lambda * lambda);
            let step = jac.transpose() * jjt.lu().solve(&e)?;
            let trial: Vec<f64> = (0..n)
                .map(|i| {
                    // Bounded steps keep the linearisation honest far from the goal.
                    let dq = step[i].clamp(-0.5, 0.5);
                    (q[i] + dq).clamp(self.joints[i].min_rad, self.joints[i].max_rad)
                })
                .collect();
            let e_trial = self.error(&trial, goal);
            if e_trial.norm() < e.norm() {
                q = trial;
                e = e_trial;
                lambda = (lambda * 0.5).max(1e-6);
            } else {
                lambda *= 4.0;
                if lambda > 1e3 {
                    break;
                }
            }
        }
        converged(&e).then_some(q)
    }

    /// d(error)/dq by forward differences (the error decreases as q approaches the goal, so
    /// the step solves J·dq = e with J = -d(error)/dq).
    fn jacobian(&self, q: &[f64], goal: &Isometry3<f64>, e: &DVector<f64>) -> DMatrix<f64> {
        const H: f64 = 1e-7;
        let mut jac = DMatrix::zeros(6, self.dof());
        let mut qh = q.to_vec();
        for i in 0..self.dof() {
            qh[i] = q[i] + H;
            let eh = self.error(&qh, goal);
            jac.set_column(i, &((e - eh) / H));
            qh[i] = q[i];
        }
        jac
    }
}

fn converged(e: &DVector<f64>) -> bool {
    let p = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let r = (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]).sqrt();
    p < POS_TOL_M && r < ROT_TOL_RAD
}

/// A number in [0, 1) from a fixed-seed xorshift: the search is deterministic.
fn next_unit(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn to_pose(t: &Isometry3<f64>) -> Pose {
    let (rx, ry, rz) = t.rotation.euler_angles();
    let p = t.translation.vector;
    Pose::new([p.x, p.y, p.z], [rx, ry, rz])
}

fn to_isometry(p: &Pose) -> Isometry3<f64> {
    let [x, y, z] = p.position_m;
    let [rx, ry, rz] = p.euler_rad;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(rx, ry, rz),
    )
}

/// `ARM_OUT_OF_RANGE` for a pose no joint solution reaches: the one code every backend uses
/// for an unreachable pose, in IK and in Cartesian moves alike.
pub(crate) fn unreachable(pose: &Pose) -> ArmError {
    ArmError::new(
        AbcErrorCode::ArmOutOfRange,
        format!("no joint solution within the limits reaches {pose:?}"),
    )
}

/// Position distance (m) and rotation angle (rad) between two poses.
pub fn pose_distance(a: &Pose, b: &Pose) -> (f64, f64) {
    let (ta, tb) = (to_isometry(a), to_isometry(b));
    let dp = (ta.translation.vector - tb.translation.vector).norm();
    let dr = ta.rotation.angle_to(&tb.rotation);
    (dp, dr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// RM65-B from its MDH table: (a mm, alpha °, d mm, offset °), ±178° everywhere except
    /// J2 ±130°, J3 ±135°, J5 ±128°, J6 ±360°.
    fn rm65b() -> Chain {
        let rows = [
            (0.0, 0.0, 240.5, 0.0, 178.0),
            (0.0, 90.0, 0.0, 90.0, 130.0),
            (256.0, 0.0, 0.0, 90.0, 135.0),
            (0.0, 90.0, 210.0, 0.0, 178.0),
            (0.0, -90.0, 0.0, 0.0, 128.0),
            (0.0, 90.0, 144.0, 0.0, 360.0),
        ];
        Chain::new(
            rows.iter()
                .map(|&(a, alpha, d, off, lim)| MdhJoint {
                    a_m: a / 1000.0,
                    alpha_rad: f64::to_radians(alpha),
                    d_m: d / 1000.0,
                    offset_rad: f64::to_radians(off),
                    min_rad: -f64::to_radians(lim),
                    max_rad: f64::to_radians(lim),
                })
                .collect(),
        )
    }

    fn deg(v: &[f64]) -> Vec<f64> {
        v.iter().map(|d| d.to_radians()).collect()
    }

    #[test]
    fn rm65b_forward_kinematics_matches_the_vendor_anchors() {
        let c = rm65b();
        let (dp, dr) = pose_distance(
            &c.forward(&[0.0; 6]),
            &Pose::new([0.0, 0.0, 0.8505], [0.0, 0.0, PI]),
        );
        assert!(dp < 1e-9 && dr < 1e-9, "{dp} {dr}");
        let p = c.forward(&deg(&[10.0, 20.0, 30.0, 40.0, 50.0, 60.0]));
        let want = [-0.35566, -0.13471, 0.61081, 1.60716, 0.00837, -0.88074];
        let got = [
            p.position_m[0],
            p.position_m[1],
            p.position_m[2],
            p.euler_rad[0],
            p.euler_rad[1],
            p.euler_rad[2],
        ];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-5, "{got:?}");
        }
    }

    #[test]
    fn work_and_tool_frames_move_the_reported_pose() {
        // At q = 0 the RM65-B flange points straight up (its z axis is the base's z).
        let tool = Pose::new([0.0, 0.0, 0.1], [0.0, 0.0, 0.0]);
        let work = Pose::new([0.0, 0.0, 0.5], [0.0, 0.0, PI / 2.0]);
        let c = rm65b().with_frames(&work, &tool);
        let p = c.forward(&[0.0; 6]);
        let (dp, dr) = pose_distance(&p, &Pose::new([0.0, 0.0, 0.4505], [0.0, 0.0, PI / 2.0]));
        assert!(dp < 1e-9 && dr < 1e-9, "{p:?}");
        // IK answers in the same frames.
        let q = deg(&[10.0, 20.0, 30.0, 40.0, 50.0, 60.0]);
        let target = c.forward(&q);
        let sol = c.inverse(&target, &q, IkMode::SingleStep).unwrap();
        assert!(pose_distance(&c.forward(&sol), &target).0 < 1e-6);
    }

    #[test]
    fn inverse_recovers_a_pose_from_a_nearby_seed() {
        let c = rm65b();
        let q = deg(&[10.0, 20.0, 30.0, 40.0, 50.0, 60.0]);
        let target = c.forward(&q);
        let seed = deg(&[5.0, 15.0, 35.0, 30.0, 45.0, 50.0]);
        let sol = c
            .inverse(&target, &seed, IkMode::SingleStep)
            .expect("solution");
        let (dp, dr) = pose_distance(&c.forward(&sol), &target);
        assert!(dp < 1e-5 && dr < 1e-5, "{dp} {dr}");
        assert!(c.within_limits(&sol));
    }

    #[test]
    fn the_search_finds_poses_a_far_seed_misses_and_rejects_the_unreachable() {
        let c = rm65b();
        let target = c.forward(&deg(&[-60.0, 40.0, 70.0, -30.0, 60.0, 20.0]));
        let sol = c
            .inverse(&target, &[0.0; 6], IkMode::IterativeSearch)
            .expect("search solution");
        let (dp, dr) = pose_distance(&c.forward(&sol), &target);
        assert!(dp < 1e-5 && dr < 1e-5, "{dp} {dr}");
        // 2 m away: beyond the 0.85 m reach.
        let far = Pose::new([2.0, 0.0, 0.3], [PI, 0.0, 0.0]);
        assert!(c
            .inverse(&far, &[0.0; 6], IkMode::IterativeSearch)
            .is_none());
        assert!(c.inverse(&far, &[0.0; 6], IkMode::SingleStep).is_none());
    }
}
