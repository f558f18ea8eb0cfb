//! Cartesian path geometry of MOVE L and MOVE C: evenly spaced poses on a line or an arc.

use nalgebra::{Isometry3, Vector3};

/// Spacing of Cartesian path samples, m and rad.
const PATH_STEP_M: f64 = 0.002;
const PATH_STEP_RAD: f64 = 0.02;
const PATH_MAX_SAMPLES: usize = 600;

/// Length of the polyline through `poses`, m.
pub(super) fn path_length(poses: &[Isometry3<f64>]) -> f64 {
    poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum()
}

/// Evenly spaced poses on the straight line from `a` to `b` (slerped orientation).
pub(super) fn line_samples(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vec<Isometry3<f64>> {
    let dist = (b.translation.vector - a.translation.vector).norm();
    let angle = a.rotation.angle_to(&b.rotation);
    let n = ((dist / PATH_STEP_M).max(angle / PATH_STEP_RAD).ceil() as usize)
        .clamp(1, PATH_MAX_SAMPLES);
    (0..=n)
        .map(|i| a.lerp_slerp(b, i as f64 / n as f64))
        .collect()
}

/// Poses on the circle through three points, from `a` via `b` to `c`; `None` when the points
/// are (nearly) collinear.
pub(super) fn arc_samples(
    a: &Isometry3<f64>,
    b: &Isometry3<f64>,
    c: &Isometry3<f64>,
) -> Option<Vec<Isometry3<f64>>> {
    let (p1, p2, p3) = (
        a.translation.vector,
        b.translation.vector,
        c.translation.vector,
    );
    let (u, w) = (p2 - p1, p3 - p1);
    let n = u.cross(&w);
    let n2 = n.norm_squared();
    if n2 < 1e-12 {
        return None;
    }
    // Circumcentre of the triangle.
    let center =
        p1 + (w.norm_squared() * n.cross(&u) + u.norm_squared() * w.cross(&n)) / (2.0 * n2);
    let r1 = p1 - center;
    let radius = r1.norm();
    let axis = n.normalize();
    let angle_of = |p: Vector3<f64>| {
        let r = p - center;
        let x = r1.normalize();
        let y = axis.cross(&x);
        let ang = r.dot(&y).atan2(r.dot(&x));
        if ang < 0.0 {
            ang + 2.0 * std::f64::consts::PI
        } else {
            ang
        }
    };
    // Going around `axis` from p1, p2 comes before p3 by construction of the normal.
    let total = angle_of(p3);
    let count = ((radius * total / PATH_STEP_M).ceil() as usize).clamp(2, PATH_MAX_SAMPLES);
    let x = r1.normalize();
    let y = axis.cross(&x);
    Some(
        (0..=count)
            .map(|i| {
                let f = i as f64 / count as f64;
                let th = total * f;
                let p = center + radius * (th.cos() * x + th.sin() * y);
                let rot = a.rotation.slerp(&c.rotation, f);
                Isometry3::from_parts(p.into(), rot)
            })
            .collect(),
    )
}
