//! Cartesian moves (`movel`, `movec`, `moves`): a geometric flange path turned into joint
//! angles by IK on a fine grid of the path fraction, then timed by one trapezoid that respects
//! the line, angular and joint limits (see the parent module's docs).

use nalgebra::Isometry3;

use super::{
    check_joints, speed_fraction, CartesianLimits, JointPath, MotionKind, PlanError, Profile,
    Trajectory,
};
use crate::realman::kinematics::{forward_isometry, inverse, Pose};
use crate::realman::model::ArmModel;
use crate::realman::path::{ArcPath, CartesianPath, LinePath, SplinePath};

/// Largest grid spacing along a Cartesian path: 1 mm of travel …
const GRID_STEP_M: f64 = 0.001;
/// … and 0.01 rad of rotation.
const GRID_STEP_RAD: f64 = 0.01;
/// Most grid points one Cartesian motion may have (200 m of path).
pub const MAX_GRID_POINTS: usize = 200_000;
/// A joint moving more than this between neighbouring grid points means the IK changed
/// branch or the path passes (too) close to a singularity, rad.
const MAX_GRID_JUMP_RAD: f64 = 0.1;

/// Joint angles along `path` on a uniform grid of s, each IK seeded with the previous point.
fn joint_grid(
    model: &ArmModel,
    from_rad: &[f64],
    path: &dyn CartesianPath,
) -> Result<Vec<Vec<f64>>, PlanError> {
    let by_length = (path.length_m() / GRID_STEP_M).ceil();
    let by_rotation = (path.rotation_rad() / GRID_STEP_RAD).ceil();
    let n = by_length.max(by_rotation).max(1.0);
    if n.is_nan() || n > MAX_GRID_POINTS as f64 {
        return Err(PlanError::TooLong {
            points: if n.is_finite() {
                n as usize
            } else {
                usize::MAX
            },
            limit: MAX_GRID_POINTS,
        });
    }
    let n = n as usize;
    let mut points = Vec::with_capacity(n + 1);
    points.push(from_rad.to_vec());
    for i in 1..=n {
        let fraction = i as f64 / n as f64;
        let pose = Pose::from_isometry(&path.pose_at(fraction));
        let prev = &points[i - 1];
        let q = inverse(model, &pose, prev)
            .map_err(|source| PlanError::Unreachable { fraction, source })?;
        if let Some((joint, jump)) = q
            .iter()
            .zip(prev)
            .map(|(a, b)| (a - b).abs())
            .enumerate()
            .find(|(_, d)| *d > MAX_GRID_JUMP_RAD)
        {
            return Err(PlanError::Singular {
                joint,
                jump_deg: jump.to_degrees(),
                fraction,
            });
        }
        points.push(q);
    }
    Ok(points)
}

fn check_cartesian_limits(limits: &CartesianLimits) -> Result<(), PlanError> {
    let all = [
        limits.line_speed_m_s,
        limits.line_acc_m_s2,
        limits.angular_speed_rad_s,
        limits.angular_acc_rad_s2,
    ];
    if all.iter().all(|v| v.is_finite() && *v > 0.0) {
        Ok(())
    } else {
        Err(PlanError::BadInput {
            reason: format!("Cartesian limits must be positive: {limits:?}"),
        })
    }
}

/// Plans a Cartesian path: IK on the grid, then one trapezoid in s limited by `v %` of the
/// line and angular speeds, the line and angular accelerations, and the joint speed and
/// acceleration limits along the path (|dq/ds| · ṡ ≤ q̇_max, |dq/ds| · s̈ ≤ q̈_max).
fn plan_cartesian(
    model: &ArmModel,
    from_rad: &[f64],
    path: &dyn CartesianPath,
    speed_percent: f64,
    limits: &CartesianLimits,
    kind: MotionKind,
) -> Result<Trajectory, PlanError> {
    check_cartesian_limits(limits)?;
    // An unreachable target is the common failure: report it as such (fraction 1) before
    // walking the path, which would otherwise fail somewhere on the way.
    let end = Pose::from_isometry(&path.pose_at(1.0));
    inverse(model, &end, from_rad).map_err(|source| PlanError::Unreachable {
        fraction: 1.0,
        source,
    })?;
    let points = joint_grid(model, from_rad, path)?;
    let f = speed_fraction(speed_percent);
    let (length, rotation) = (path.length_m(), path.rotation_rad());
    let mut speed = f64::INFINITY;
    let mut acc = f64::INFINITY;
    if length > 0.0 {
        speed = speed.min(limits.line_speed_m_s * f / length);
        acc = acc.min(limits.line_acc_m_s2 / length);
    }
    if rotation > 0.0 {
        speed = speed.min(limits.angular_speed_rad_s * f / rotation);
        acc = acc.min(limits.angular_acc_rad_s2 / rotation);
    }
    let (vmax, amax) = (model.max_speed_rad_s(), model.max_acc_rad_s2());
    let n = (points.len() - 1) as f64;
    for w in points.windows(2) {
        for j in 0..model.dof {
            let dqds = (w[1][j] - w[0][j]).abs() * n;
            if dqds > 0.0 {
                speed = speed.min(vmax[j] / dqds);
                acc = acc.min(amax[j] / dqds);
            }
        }
    }
    Ok(Trajectory::single(
        kind,
        Profile::new(speed, acc),
        JointPath::Grid { points },
    ))
}

/// A straight line of the flange from where `from_rad` puts it to `to` (`movel`), orientation
/// slerped, at `speed_percent` of `limits` (see the module docs).
pub fn plan_linear(
    model: &ArmModel,
    from_rad: &[f64],
    to: &Pose,
    speed_percent: f64,
    limits: &CartesianLimits,
) -> Result<Trajectory, PlanError> {
    check_joints(model, from_rad, "start")?;
    check_pose(to)?;
    let path = LinePath::new(forward_isometry(model, from_rad), to.to_isometry());
    plan_cartesian(
        model,
        from_rad,
        &path,
        speed_percent,
        limits,
        MotionKind::Linear,
    )
}

/// A circular arc of the flange from where `from_rad` puts it, through `via`, to `to`,
/// with `loops` extra full turns before stopping at `to` (`movec`). The orientation is
/// slerped from the start to `to`'s orientation over the whole motion.
pub fn plan_circle(
    model: &ArmModel,
    from_rad: &[f64],
    via: &Pose,
    to: &Pose,
    speed_percent: f64,
    loops: u32,
    limits: &CartesianLimits,
) -> Result<Trajectory, PlanError> {
    check_joints(model, from_rad, "start")?;
    check_pose(via)?;
    check_pose(to)?;
    let start = forward_isometry(model, from_rad);
    let path = ArcPath::new(&start, &via.to_isometry(), &to.to_isometry(), loops)?;
    plan_cartesian(
        model,
        from_rad,
        &path,
        speed_percent,
        limits,
        MotionKind::Circle,
    )
}

/// Least number of points a `moves` spline needs besides the start (§3).
pub const SPLINE_MIN_POINTS: usize = 3;

/// A smooth curve of the flange from where `from_rad` puts it through every pose of `points`
/// in order (`moves`): a Catmull-Rom spline in position travelled at constant speed between
/// the ramps, orientation slerped from point to point.
pub fn plan_spline(
    model: &ArmModel,
    from_rad: &[f64],
    points: &[Pose],
    speed_percent: f64,
    limits: &CartesianLimits,
) -> Result<Trajectory, PlanError> {
    check_joints(model, from_rad, "start")?;
    if points.len() < SPLINE_MIN_POINTS {
        return Err(PlanError::TooFewPoints {
            needed: SPLINE_MIN_POINTS,
            got: points.len(),
        });
    }
    for p in points {
        check_pose(p)?;
    }
    let mut knots: Vec<Isometry3<f64>> = vec![forward_isometry(model, from_rad)];
    knots.extend(points.iter().map(Pose::to_isometry));
    let path = SplinePath::new(knots);
    plan_cartesian(
        model,
        from_rad,
        &path,
        speed_percent,
        limits,
        MotionKind::Spline,
    )
}

fn check_pose(p: &Pose) -> Result<(), PlanError> {
    if p.is_finite() {
        Ok(())
    } else {
        Err(PlanError::BadInput {
            reason: format!("pose is not finite: {p:?}"),
        })
    }
}
