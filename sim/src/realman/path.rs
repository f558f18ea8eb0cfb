//! Geometric flange paths for the Cartesian planners: a pose as a function of the path
//! fraction s ∈ [0, 1], with the path's length and total rotation (to time it).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::planner::PlanError;

/// A flange path: pose at s ∈ [0, 1], s proportional to distance along the path (or to the
/// rotation when the position does not move).
pub(crate) trait CartesianPath {
    /// Pose at fraction `s`.
    fn pose_at(&self, s: f64) -> Isometry3<f64>;
    /// Length of the position path, m.
    fn length_m(&self) -> f64;
    /// Total rotation along the path, rad.
    fn rotation_rad(&self) -> f64;
}

/// Rotation from `a` towards `b` by fraction `s` about their relative axis (a slerp that
/// cannot panic at 180°).
pub(crate) fn slerp(
    a: &UnitQuaternion<f64>,
    b: &UnitQuaternion<f64>,
    s: f64,
) -> UnitQuaternion<f64> {
    let rel = (a.inverse() * b).scaled_axis();
    a * UnitQuaternion::from_scaled_axis(rel * s)
}

/// Angle between two orientations, rad.
fn angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    (a.inverse() * b).angle()
}

fn iso(p: Vector3<f64>, r: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(p), r)
}

/// Straight line with orientation slerp (`movel`).
pub(crate) struct LinePath {
    from: Isometry3<f64>,
    to: Isometry3<f64>,
}

impl LinePath {
    pub(crate) fn new(from: Isometry3<f64>, to: Isometry3<f64>) -> Self {
        Self { from, to }
    }
}

impl CartesianPath for LinePath {
    fn pose_at(&self, s: f64) -> Isometry3<f64> {
        let a = self.from.translation.vector;
        let b = self.to.translation.vector;
        iso(
            a + (b - a) * s,
            slerp(&self.from.rotation, &self.to.rotation, s),
        )
    }
    fn length_m(&self) -> f64 {
        (self.to.translation.vector - self.from.translation.vector).norm()
    }
    fn rotation_rad(&self) -> f64 {
        angle_between(&self.from.rotation, &self.to.rotation)
    }
}

/// Circular arc from the start through `via` to `to`, plus whole turns (`movec` with `loop`).
/// Orientation is slerped from the start to `to` over the whole path (the via orientation is
/// not used).
pub(crate) struct ArcPath {
    centre: Vector3<f64>,
    radius_vec: Vector3<f64>,
    normal: Vector3<f64>,
    sweep_rad: f64,
    from_rot: UnitQuaternion<f64>,
    to_rot: UnitQuaternion<f64>,
}

impl ArcPath {
    /// The arc through the three positions; [`PlanError::DegenerateArc`] when they are
    /// (nearly) collinear or two coincide.
    pub(crate) fn new(
        from: &Isometry3<f64>,
        via: &Isometry3<f64>,
        to: &Isometry3<f64>,
        loops: u32,
    ) -> Result<Self, PlanError> {
        let p0 = from.translation.vector;
        let u = via.translation.vector - p0;
        let w = to.translation.vector - p0;
        let n = u.cross(&w);
        // 0.1 mm of sagitta-scale area: below this the three points do not define a circle.
        let min_len = 1e-4;
        if u.norm() < min_len || w.norm() < min_len || (w - u).norm() < min_len {
            return Err(PlanError::DegenerateArc);
        }
        if n.norm() < 1e-3 * u.norm() * w.norm() {
            return Err(PlanError::DegenerateArc);
        }
        // Circumcentre of the triangle (p0, p0 + u, p0 + w).
        let centre = p0
            + (u * w.norm_squared() - w * u.norm_squared()).cross(&n) / (-2.0 * n.norm_squared());
        let normal = n.normalize();
        let r0 = p0 - centre;
        let r2 = to.translation.vector - centre;
        // (p0, via, to) run counter-clockwise about n = u × w, so the arc to `to` is its
        // counter-clockwise angle, in (0, 2π).
        let phi = normal.dot(&r0.cross(&r2)).atan2(r0.dot(&r2));
        let phi = if phi <= 0.0 {
            phi + std::f64::consts::TAU
        } else {
            phi
        };
        Ok(Self {
            centre,
            radius_vec: r0,
            normal,
            sweep_rad: phi + std::f64::consts::TAU * f64::from(loops),
            from_rot: from.rotation,
            to_rot: to.rotation,
        })
    }
}

impl CartesianPath for ArcPath {
    fn pose_at(&self, s: f64) -> Isometry3<f64> {
        let turn = UnitQuaternion::from_scaled_axis(self.normal * (self.sweep_rad * s));
        iso(
            self.centre + turn * self.radius_vec,
            slerp(&self.from_rot, &self.to_rot, s),
        )
    }
    fn length_m(&self) -> f64 {
        self.radius_vec.norm() * self.sweep_rad
    }
    fn rotation_rad(&self) -> f64 {
        angle_between(&self.from_rot, &self.to_rot)
    }
}

/// Sub-steps per spline segment of the arc-length table.
const SPLINE_TABLE_STEPS: usize = 64;

/// Catmull-Rom spline through the start and the given points (`moves`), parametrised by arc
/// length; orientation slerped point to point, in step with the segment being travelled.
pub(crate) struct SplinePath {
    points: Vec<Isometry3<f64>>,
    /// (segment parameter g = segment index + u, arc length from the start), increasing.
    table: Vec<(f64, f64)>,
    rotation_rad: f64,
}

impl SplinePath {
    /// Needs the start and at least one more point (the caller enforces the command minimum).
    pub(crate) fn new(points: Vec<Isometry3<f64>>) -> Self {
        let mut path = Self {
            points,
            table: Vec::new(),
            rotation_rad: 0.0,
        };
        let segments = path.points.len().saturating_sub(1);
        let mut length = 0.0;
        let mut last = path.position(0.0);
        path.table.push((0.0, 0.0));
        for k in 1..=segments * SPLINE_TABLE_STEPS {
            let g = k as f64 / SPLINE_TABLE_STEPS as f64;
            let p = path.position(g);
            length += (p - last).norm();
            last = p;
            path.table.push((g, length));
        }
        path.rotation_rad = path
            .points
            .windows(2)
            .map(|w| angle_between(&w[0].rotation, &w[1].rotation))
            .sum();
        path
    }

    fn point(&self, i: isize) -> Vector3<f64> {
        let n = self.points.len() as isize;
        let at = |k: isize| self.points[k.clamp(0, n - 1) as usize].translation.vector;
        // Phantom end points mirror their neighbour, so the curve starts and ends in the
        // direction of the first / last chord.
        if i < 0 {
            2.0 * at(0) - at(1.min(n - 1))
        } else if i >= n {
            2.0 * at(n - 1) - at((n - 2).max(0))
        } else {
            at(i)
        }
    }

    /// Position at segment parameter `g` (segment index + fraction).
    fn position(&self, g: f64) -> Vector3<f64> {
        let segments = self.points.len().saturating_sub(1);
        if segments == 0 {
            return self.point(0);
        }
        let i = (g.floor().max(0.0) as usize).min(segments - 1);
        let u = (g - i as f64).clamp(0.0, 1.0);
        let i = i as isize;
        let (p0, p1, p2, p3) = (
            self.point(i - 1),
            self.point(i),
            self.point(i + 1),
            self.point(i + 2),
        );
        let (u2, u3) = (u * u, u * u * u);
        0.5 * (p1 * 2.0
            + (p2 - p0) * u
            + (p0 * 2.0 - p1 * 5.0 + p2 * 4.0 - p3) * u2
            + (p1 * 3.0 - p0 - p2 * 3.0 + p3) * u3)
    }

    /// Segment parameter at fraction `s` of the arc length.
    fn param_at(&self, s: f64) -> f64 {
        let total = self.length_m();
        let Some(&(g_end, _)) = self.table.last() else {
            return 0.0;
        };
        if total <= 0.0 {
            return g_end * s.clamp(0.0, 1.0);
        }
        let want = s.clamp(0.0, 1.0) * total;
        let k = self.table.partition_point(|&(_, l)| l < want);
        if k == 0 {
            return 0.0;
        }
        if k >= self.table.len() {
            return g_end;
        }
        let (g0, l0) = self.table[k - 1];
        let (g1, l1) = self.table[k];
        if l1 - l0 <= 0.0 {
            g1
        } else {
            g0 + (g1 - g0) * (want - l0) / (l1 - l0)
        }
    }
}

impl CartesianPath for SplinePath {
    fn pose_at(&self, s: f64) -> Isometry3<f64> {
        let g = self.param_at(s);
        let segments = self.points.len().saturating_sub(1);
        let rot = if segments == 0 {
            self.points[0].rotation
        } else {
            let i = (g.floor().max(0.0) as usize).min(segments - 1);
            let u = (g - i as f64).clamp(0.0, 1.0);
            slerp(&self.points[i].rotation, &self.points[i + 1].rotation, u)
        };
        iso(self.position(g), rot)
    }
    fn length_m(&self) -> f64 {
        self.table.last().map_or(0.0, |&(_, l)| l)
    }
    fn rotation_rad(&self) -> f64 {
        self.rotation_rad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64, y: f64, z: f64) -> Isometry3<f64> {
        iso(Vector3::new(x, y, z), UnitQuaternion::identity())
    }

    #[test]
    fn arc_passes_through_its_three_points() {
        let a = at(0.3, 0.0, 0.4);
        let v = at(0.3, 0.1, 0.5);
        let b = at(0.3, 0.0, 0.6);
        let arc = ArcPath::new(&a, &v, &b, 0).expect("arc");
        assert!((arc.length_m() - 0.1 * std::f64::consts::PI).abs() < 1e-12);
        let end = arc.pose_at(1.0).translation.vector;
        assert!((end - b.translation.vector).norm() < 1e-12);
        let mid = arc.pose_at(0.5).translation.vector;
        assert!((mid - v.translation.vector).norm() < 1e-12, "{mid}");
        let looped = ArcPath::new(&a, &v, &b, 2).expect("arc");
        assert!((looped.length_m() - 0.1 * 5.0 * std::f64::consts::PI).abs() < 1e-12);
        assert!(ArcPath::new(&a, &at(0.3, 0.0, 0.5), &b, 0).is_err());
    }

    #[test]
    fn spline_interpolates_its_points_by_arc_length() {
        let pts = vec![
            at(0.3, 0.0, 0.4),
            at(0.35, 0.05, 0.45),
            at(0.4, 0.0, 0.5),
            at(0.35, -0.05, 0.55),
        ];
        let sp = SplinePath::new(pts.clone());
        assert!((sp.pose_at(0.0).translation.vector - pts[0].translation.vector).norm() < 1e-12);
        assert!((sp.pose_at(1.0).translation.vector - pts[3].translation.vector).norm() < 1e-12);
        // Equal steps of s give (nearly) equal steps of distance.
        let n = 200;
        let step = sp.length_m() / n as f64;
        for i in 0..n {
            let a = sp.pose_at(i as f64 / n as f64).translation.vector;
            let b = sp.pose_at((i + 1) as f64 / n as f64).translation.vector;
            assert!(((b - a).norm() - step).abs() < 0.02 * step, "step {i}");
        }
    }
}
