//! Motion planning as the controller does it for `movej`, `movel`, `movec`, `moves` and
//! connected (`trajectory_connect`) queues (`docs/protocols/realman.md` §3, §8).
//!
//! Every motion is planned completely before it starts, so a target that is out of reach or
//! beyond a joint limit anywhere on the path is refused ([`PlanError`]) while the arm is still
//! at rest.
//!
//! - **Joint moves** ([`plan_joint`]) go in a straight line in joint space; all joints start and
//!   stop together. One trapezoidal profile on the path fraction s ∈ [0, 1] is limited so that
//!   no joint exceeds `v %` of its maximum speed or its maximum acceleration.
//! - **Cartesian moves** ([`plan_linear`], [`plan_circle`], [`plan_spline`]) are a geometric
//!   flange path (position and orientation as a function of s) turned into joint angles by IK
//!   on a fine grid of s (≤ 1 mm and ≤ 0.01 rad apart), then timed by one trapezoid in s whose
//!   speed and acceleration respect `v %` of the line and angular limits ([`CartesianLimits`])
//!   and the joint speed limits along the path.
//! - **Blending** ([`blend`]) joins two trajectories; with radius `r %` the next one starts
//!   before the previous one has stopped: the overlap is `r %` of the shorter of the previous
//!   segment's deceleration and the next one's acceleration, and the joint *displacements* of
//!   both are added in that window. The arm never stops at the junction, the corner is rounded,
//!   and with `r = 0` the segments simply run back to back. Splines are never blended (§3).
//!   In the overlap a joint moving the same way in both segments can briefly exceed either
//!   segment's own peak speed (at most their sum); the Cartesian path leaves the two lines
//!   there, which is what a blend radius is for.

use super::kinematics::{inverse, IkError, Pose};
use super::model::ArmModel;

mod cartesian;
#[cfg(test)]
mod tests;

pub use cartesian::{plan_circle, plan_linear, plan_spline, MAX_GRID_POINTS, SPLINE_MIN_POINTS};

/// End-effector motion limits (§8); `Default` is the controller's `set_arm_init` values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartesianLimits {
    /// Maximum line speed, m/s.
    pub line_speed_m_s: f64,
    /// Maximum line acceleration, m/s².
    pub line_acc_m_s2: f64,
    /// Maximum angular speed, rad/s.
    pub angular_speed_rad_s: f64,
    /// Maximum angular acceleration, rad/s².
    pub angular_acc_rad_s2: f64,
}

impl Default for CartesianLimits {
    fn default() -> Self {
        Self {
            line_speed_m_s: 0.25,
            line_acc_m_s2: 1.6,
            angular_speed_rad_s: 0.6,
            angular_acc_rad_s2: 4.0,
        }
    }
}

/// What kind of motion a trajectory (segment) is: what `get_arm_current_trajectory` reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MotionKind {
    /// Joint-space move (`movej`, `movej_p`).
    Joint,
    /// Straight line (`movel`).
    Linear,
    /// Circular arc (`movec`).
    Circle,
    /// Spline through points (`moves`).
    Spline,
}

/// Why a motion cannot be planned. Nothing has moved when this is returned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// A joint vector has the wrong length or a value is not finite.
    #[error("bad input: {reason}")]
    BadInput {
        /// What is wrong.
        reason: String,
    },
    /// A joint target lies outside its range.
    #[error("joint {joint} target {value_deg:.3}° outside [{min_deg}, {max_deg}]°")]
    OutOfLimits {
        /// 0-based joint index.
        joint: usize,
        /// The requested angle, °.
        value_deg: f64,
        /// Lower limit, °.
        min_deg: f64,
        /// Upper limit, °.
        max_deg: f64,
    },
    /// IK found no joint angles at some point of a Cartesian path.
    #[error("no IK solution at {:.1} % of the path: {source}", fraction * 100.0)]
    Unreachable {
        /// Path fraction (0 = start, 1 = target) of the first failing point.
        fraction: f64,
        /// The IK's reason.
        source: IkError,
    },
    /// The joint angles jump between neighbouring path points: the path crosses a singularity
    /// or the IK changed branch.
    #[error("joint {joint} jumps {jump_deg:.2}° at {:.1} % of the path (singularity)", fraction * 100.0)]
    Singular {
        /// 0-based joint index.
        joint: usize,
        /// Size of the jump, °.
        jump_deg: f64,
        /// Path fraction where it happens.
        fraction: f64,
    },
    /// The three points of a circle are (nearly) collinear or coincide.
    #[error("the circle's points are collinear or coincide")]
    DegenerateArc,
    /// Too few points for the motion.
    #[error("{got} points given, at least {needed} needed")]
    TooFewPoints {
        /// Minimum count.
        needed: usize,
        /// Count given.
        got: usize,
    },
    /// Two trajectories to blend do not meet: the second does not start where the first ends.
    #[error("joint {joint}: next segment starts {gap_deg:.3}° away from the previous end")]
    Discontinuous {
        /// 0-based joint index.
        joint: usize,
        /// Gap, °.
        gap_deg: f64,
    },
    /// The path needs more grid points than the planner allows (e.g. thousands of loops).
    #[error("path too long: {points} grid points (limit {limit})")]
    TooLong {
        /// Grid points needed.
        points: usize,
        /// The limit.
        limit: usize,
    },
}

/// A rest-to-rest trapezoidal profile of the path fraction s from 0 to 1.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Profile {
    /// Acceleration of s, 1/s².
    acc: f64,
    /// Peak speed of s, 1/s.
    peak: f64,
    /// Duration of the acceleration (= deceleration) phase, s.
    ramp_s: f64,
    /// Total duration, s.
    total_s: f64,
}

impl Profile {
    /// The fastest profile with |ṡ| ≤ `speed` and |s̈| ≤ `acc` (both > 0, may be ∞ for an
    /// empty path, which gives a zero-length profile).
    fn new(speed: f64, acc: f64) -> Self {
        if !(speed.is_finite() && acc.is_finite()) || speed <= 0.0 || acc <= 0.0 {
            return Self {
                acc: 0.0,
                peak: 0.0,
                ramp_s: 0.0,
                total_s: 0.0,
            };
        }
        if speed * speed >= acc {
            // Triangle: never reaches `speed`.
            let ramp_s = (1.0 / acc).sqrt();
            Self {
                acc,
                peak: acc * ramp_s,
                ramp_s,
                total_s: 2.0 * ramp_s,
            }
        } else {
            let ramp_s = speed / acc;
            Self {
                acc,
                peak: speed,
                ramp_s,
                total_s: 1.0 / speed + ramp_s,
            }
        }
    }

    /// s and ṡ at time `t` (clamped to the profile).
    fn at(&self, t: f64) -> (f64, f64) {
        if self.total_s <= 0.0 || t >= self.total_s {
            return (1.0, 0.0);
        }
        if t <= 0.0 {
            return (0.0, 0.0);
        }
        if t < self.ramp_s {
            (0.5 * self.acc * t * t, self.acc * t)
        } else if t <= self.total_s - self.ramp_s {
            (
                0.5 * self.acc * self.ramp_s * self.ramp_s + self.peak * (t - self.ramp_s),
                self.peak,
            )
        } else {
            let r = self.total_s - t;
            (1.0 - 0.5 * self.acc * r * r, self.acc * r)
        }
    }
}

/// The joint path of one segment as a function of s.
#[derive(Debug, Clone, PartialEq)]
enum JointPath {
    /// Straight line in joint space.
    Line { from: Vec<f64>, to: Vec<f64> },
    /// Joint angles on a uniform grid of s (`points[i]` at s = i / (len − 1)), interpolated
    /// by cubic Hermite splines.
    Grid { points: Vec<Vec<f64>> },
}

impl JointPath {
    fn start(&self) -> &[f64] {
        match self {
            Self::Line { from, .. } => from,
            Self::Grid { points } => &points[0],
        }
    }

    fn end(&self) -> &[f64] {
        match self {
            Self::Line { to, .. } => to,
            Self::Grid { points } => &points[points.len() - 1],
        }
    }

    /// q(s) and dq/ds.
    fn at(&self, s: f64) -> (Vec<f64>, Vec<f64>) {
        match self {
            Self::Line { from, to } => {
                let d: Vec<f64> = to.iter().zip(from).map(|(b, a)| b - a).collect();
                let q = from.iter().zip(&d).map(|(a, d)| a + s * d).collect();
                (q, d)
            }
            Self::Grid { points } => {
                let n = points.len() - 1;
                if n == 0 {
                    return (points[0].clone(), vec![0.0; points[0].len()]);
                }
                let x = s.clamp(0.0, 1.0) * n as f64;
                let i = (x.floor() as usize).min(n - 1);
                let f = x - i as f64;
                // Cubic Hermite between the grid points with central-difference slopes: the
                // flange follows the Cartesian path to O(h³) between grid points (linear
                // interpolation would make its speed ripple by ~0.1 % on a 1 mm grid).
                let slope = |k: usize, j: usize| {
                    let (a, b) = (k.saturating_sub(1), (k + 1).min(n));
                    (points[b][j] - points[a][j]) / (b - a) as f64
                };
                let (f2, f3) = (f * f, f * f * f);
                let h = [
                    2.0 * f3 - 3.0 * f2 + 1.0,
                    f3 - 2.0 * f2 + f,
                    3.0 * f2 - 2.0 * f3,
                    f3 - f2,
                ];
                let dh = [
                    6.0 * f2 - 6.0 * f,
                    3.0 * f2 - 4.0 * f + 1.0,
                    6.0 * f - 6.0 * f2,
                    3.0 * f2 - 2.0 * f,
                ];
                let dof = points[0].len();
                let mut q = Vec::with_capacity(dof);
                let mut d = Vec::with_capacity(dof);
                for (j, (&p0, &p1)) in points[i].iter().zip(&points[i + 1]).enumerate() {
                    let (m0, m1) = (slope(i, j), slope(i + 1, j));
                    q.push(h[0] * p0 + h[1] * m0 + h[2] * p1 + h[3] * m1);
                    d.push((dh[0] * p0 + dh[1] * m0 + dh[2] * p1 + dh[3] * m1) * n as f64);
                }
                (q, d)
            }
        }
    }
}

/// One planned motion: a joint path, its timing, and when it starts within its trajectory.
#[derive(Debug, Clone, PartialEq)]
struct Segment {
    kind: MotionKind,
    start_s: f64,
    profile: Profile,
    path: JointPath,
}

impl Segment {
    fn end_s(&self) -> f64 {
        self.start_s + self.profile.total_s
    }
}

/// A planned motion of the arm: one segment or several blended ones. Sample it with the time
/// since the motion started; beyond [`Trajectory::duration_s`] it stays at the end.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    segments: Vec<Segment>,
}

impl Trajectory {
    fn single(kind: MotionKind, profile: Profile, path: JointPath) -> Self {
        Self {
            segments: vec![Segment {
                kind,
                start_s: 0.0,
                profile,
                path,
            }],
        }
    }

    /// Total duration, s.
    pub fn duration_s(&self) -> f64 {
        self.segments.iter().map(Segment::end_s).fold(0.0, f64::max)
    }

    /// Joint positions (rad) at `t_s` after the start.
    pub fn sample(&self, t_s: f64) -> Vec<f64> {
        self.sample_with_velocity(t_s).0
    }

    /// Joint velocities (rad/s) at `t_s`.
    pub fn velocity(&self, t_s: f64) -> Vec<f64> {
        self.sample_with_velocity(t_s).1
    }

    /// Joint positions (rad) and velocities (rad/s) at `t_s`: the start plus every segment's
    /// displacement so far (segments chain end to start, so this is each segment's own q(s)
    /// while it runs alone, and the blend of two while they overlap).
    pub fn sample_with_velocity(&self, t_s: f64) -> (Vec<f64>, Vec<f64>) {
        let mut q = self.start_rad().to_vec();
        let mut v = vec![0.0; q.len()];
        for seg in &self.segments {
            let local = t_s - seg.start_s;
            if local <= 0.0 {
                continue;
            }
            let (s, ds) = seg.profile.at(local);
            let (qs, dqds) = seg.path.at(s);
            for k in 0..q.len() {
                q[k] += qs[k] - seg.path.start()[k];
                v[k] += dqds[k] * ds;
            }
        }
        (q, v)
    }

    /// The kind of the first segment.
    pub fn kind(&self) -> MotionKind {
        self.segments[0].kind
    }

    /// The kind of the segment running at `t_s` (the latest one started, while two blend).
    pub fn kind_at(&self, t_s: f64) -> MotionKind {
        self.segments
            .iter()
            .rev()
            .find(|s| s.start_s <= t_s)
            .unwrap_or(&self.segments[0])
            .kind
    }

    /// Joint positions at the start, rad.
    pub fn start_rad(&self) -> &[f64] {
        self.segments[0].path.start()
    }

    /// Joint positions at the end, rad.
    pub fn end_rad(&self) -> &[f64] {
        self.segments[self.segments.len() - 1].path.end()
    }

    /// Number of segments (commands) in this trajectory.
    pub fn segment_count(&self) -> usize {
        self.segments.len()
    }

    /// When each segment ends, s after the start (for the controller's per-segment arrival
    /// events with `trajectory_connect: 1`); the last entry is [`Trajectory::duration_s`].
    pub fn segment_end_times_s(&self) -> Vec<f64> {
        self.segments.iter().map(Segment::end_s).collect()
    }
}

/// Checks a joint vector's length and finiteness.
fn check_joints(model: &ArmModel, q: &[f64], what: &str) -> Result<(), PlanError> {
    if q.len() != model.dof || q.iter().any(|v| !v.is_finite()) {
        return Err(PlanError::BadInput {
            reason: format!("{what} needs {} finite joint angles", model.dof),
        });
    }
    Ok(())
}

/// `Err(OutOfLimits)` for the first joint of `q` beyond its range.
fn check_limits(model: &ArmModel, q: &[f64]) -> Result<(), PlanError> {
    match model.first_out_of_limits(q) {
        None => Ok(()),
        Some(j) => Err(PlanError::OutOfLimits {
            joint: j,
            value_deg: q[j].to_degrees(),
            min_deg: model.joint_min_deg[j],
            max_deg: model.joint_max_deg[j],
        }),
    }
}

/// Speed fraction from a `v` percentage: clamped to 1–100 % (the controller accepts 0–100;
/// 0 would never arrive, so it counts as 1 %).
fn speed_fraction(speed_percent: f64) -> f64 {
    if speed_percent.is_finite() {
        speed_percent.clamp(1.0, 100.0) / 100.0
    } else {
        1.0
    }
}

/// A joint-space move from `from_rad` to `to_rad` (rad, `model.dof` each) at `speed_percent`
/// of the joint speed limits, all joints synchronised (see the module docs).
pub fn plan_joint(
    model: &ArmModel,
    from_rad: &[f64],
    to_rad: &[f64],
    speed_percent: f64,
) -> Result<Trajectory, PlanError> {
    check_joints(model, from_rad, "start")?;
    check_joints(model, to_rad, "target")?;
    check_limits(model, to_rad)?;
    let f = speed_fraction(speed_percent);
    let (vmax, amax) = (model.max_speed_rad_s(), model.max_acc_rad_s2());
    let mut speed = f64::INFINITY;
    let mut acc = f64::INFINITY;
    for j in 0..model.dof {
        let d = (to_rad[j] - from_rad[j]).abs();
        if d > 0.0 {
            speed = speed.min(vmax[j] * f / d);
            acc = acc.min(amax[j] / d);
        }
    }
    Ok(Trajectory::single(
        MotionKind::Joint,
        Profile::new(speed, acc),
        JointPath::Line {
            from: from_rad.to_vec(),
            to: to_rad.to_vec(),
        },
    ))
}

/// A joint-space move to a Cartesian target (`movej_p`): IK seeded with `from_rad`, then
/// [`plan_joint`].
pub fn plan_joint_to_pose(
    model: &ArmModel,
    from_rad: &[f64],
    to: &Pose,
    speed_percent: f64,
) -> Result<Trajectory, PlanError> {
    check_joints(model, from_rad, "start")?;
    let target = inverse(model, to, from_rad).map_err(|source| PlanError::Unreachable {
        fraction: 1.0,
        source,
    })?;
    plan_joint(model, from_rad, &target, speed_percent)
}

/// Joins `next` after `prev` with blend radius `r_percent` (0–100, see the module docs).
///
/// `next` must start where `prev` ends (within 0.001°). Splines are never blended: if either
/// side at the junction is a spline, the segments run back to back.
pub fn blend(
    prev: &Trajectory,
    next: &Trajectory,
    r_percent: f64,
) -> Result<Trajectory, PlanError> {
    for (j, (a, b)) in prev.end_rad().iter().zip(next.start_rad()).enumerate() {
        let gap_deg = (a - b).abs().to_degrees();
        if gap_deg.is_nan() || gap_deg > 1e-3 {
            return Err(PlanError::Discontinuous { joint: j, gap_deg });
        }
    }
    if prev.start_rad().len() != next.start_rad().len() {
        return Err(PlanError::BadInput {
            reason: "blended trajectories have different joint counts".to_owned(),
        });
    }
    let last = &prev.segments[prev.segments.len() - 1];
    let first = &next.segments[0];
    let r = if r_percent.is_finite() {
        r_percent.clamp(0.0, 100.0) / 100.0
    } else {
        0.0
    };
    let spline = last.kind == MotionKind::Spline || first.kind == MotionKind::Spline;
    let overlap = if spline {
        0.0
    } else {
        r * last.profile.ramp_s.min(first.profile.ramp_s)
    };
    // `next` starts when `prev` has `overlap` left (never before `prev`'s last segment starts).
    let offset = (last.end_s() - overlap).max(last.start_s);
    let mut segments = prev.segments.clone();
    segments.extend(next.segments.iter().map(|s| Segment {
        start_s: s.start_s + offset,
        ..s.clone()
    }));
    Ok(Trajectory { segments })
}
