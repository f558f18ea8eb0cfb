//! A collision mesh as the ground sees it: the vertices of its convex hull, thinned to the
//! few that span it.

use nalgebra::Point3;

/// Most contact points kept per mesh. A flat sole keeps its corners (farthest-point
/// sampling takes extremes first); more points on one face would stiffen the contact past
/// what the explicit contact springs stay stable with on a light link.
pub const MAX_CONTACT_POINTS: usize = 16;

/// Why a mesh has no contact points.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HullError {
    /// No vertices at all.
    #[error("the mesh has no vertices")]
    Empty,
}

/// The vertices of the convex hull of `points` (computed with parry3d). A flat mesh (a
/// plate, fewer than four points off one plane) has no hull of volume: its own distinct
/// points stand for it.
pub fn convex_hull_vertices(points: &[Point3<f64>]) -> Result<Vec<Point3<f64>>, HullError> {
    use parry3d::math::Vector;
    // Meshes repeat each vertex in every triangle that has it (an STL six times over): the
    // hull needs each once, and a 100,000-vertex arm link hulls several times faster so.
    let mut unique: Vec<[u32; 3]> = points
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32].map(f32::to_bits))
        .collect();
    unique.sort_unstable();
    unique.dedup();
    let input: Vec<Vector> = unique
        .iter()
        .map(|b| {
            Vector::new(
                f32::from_bits(b[0]),
                f32::from_bits(b[1]),
                f32::from_bits(b[2]),
            )
        })
        .collect();
    // parry's hull asserts on some degenerate inputs instead of returning its error; a mesh
    // of a user's robot must not take the emulator down.
    let hull = std::panic::catch_unwind(|| parry3d::transformation::try_convex_hull(&input));
    let vertices: Vec<Point3<f64>> = match hull {
        Ok(Ok((vertices, _))) if vertices.len() >= 4 => vertices
            .iter()
            .map(|v| Point3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z)))
            .collect(),
        _ => {
            let mut distinct: Vec<Point3<f64>> = Vec::new();
            for p in points {
                if !distinct.contains(p) {
                    distinct.push(*p);
                }
            }
            distinct
        }
    };
    if vertices.is_empty() {
        return Err(HullError::Empty);
    }
    Ok(vertices)
}

/// At most `most` of `points`, chosen by farthest-point sampling from the lowest one (then
/// the lowest x, y): each next point is the one farthest from those already taken, so a box
/// keeps its corners and a rounded foot a ring around its tip. Deterministic.
pub fn spread_points(points: &[Point3<f64>], most: usize) -> Vec<Point3<f64>> {
    if points.len() <= most {
        return points.to_vec();
    }
    let start = (0..points.len())
        .min_by(|&a, &b| {
            let (p, q) = (points[a], points[b]);
            (p.z, p.x, p.y)
                .partial_cmp(&(q.z, q.x, q.y))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    let mut taken = vec![points[start]];
    let mut distance: Vec<f64> = points
        .iter()
        .map(|p| (p - points[start]).norm_squared())
        .collect();
    while taken.len() < most {
        let (next, far) =
            distance.iter().enumerate().fold(
                (0, -1.0),
                |best, (i, &d)| if d > best.1 { (i, d) } else { best },
            );
        if far <= 0.0 {
            break;
        }
        taken.push(points[next]);
        for (d, p) in distance.iter_mut().zip(points) {
            *d = d.min((p - points[next]).norm_squared());
        }
    }
    taken
}

/// The contact points of a collision mesh: its hull's vertices, spread to at most
/// [`MAX_CONTACT_POINTS`].
pub fn contact_points(points: &[Point3<f64>]) -> Result<Vec<Point3<f64>>, HullError> {
    Ok(spread_points(
        &convex_hull_vertices(points)?,
        MAX_CONTACT_POINTS,
    ))
}

/// The convex parts of a triangle mesh (parry3d's V-HACD at its default resolution), each as
/// its hull's vertices; a mesh V-HACD cannot split (or that makes it panic) is one part, its
/// whole hull.
pub fn convex_parts(vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> Vec<Vec<Point3<f64>>> {
    use parry3d::math::Vector;
    use parry3d::transformation::vhacd::{VHACDParameters, VHACD};
    let input: Vec<Vector> = vertices
        .iter()
        .map(|p| Vector::new(p.x as f32, p.y as f32, p.z as f32))
        .collect();
    let parts = std::panic::catch_unwind(|| {
        VHACD::decompose(&VHACDParameters::default(), &input, triangles, false)
            .compute_convex_hulls(1)
    })
    .unwrap_or_default();
    let parts: Vec<Vec<Point3<f64>>> = parts
        .into_iter()
        .map(|(part, _)| part)
        .filter(|part| part.len() >= 4)
        .map(|part| {
            part.iter()
                .map(|v| Point3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z)))
                .collect()
        })
        .collect();
    if parts.is_empty() {
        return convex_hull_vertices(vertices).map_or_else(|_| Vec::new(), |hull| vec![hull]);
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_with_inside_points() -> Vec<Point3<f64>> {
        let mut points = Vec::new();
        for x in [-1.0, 1.0] {
            for y in [-1.0, 1.0] {
                for z in [-1.0, 1.0] {
                    points.push(Point3::new(x, y, z));
                }
            }
        }
        // Points inside the cube and on its faces are not on the hull's corners.
        points.push(Point3::new(0.1, 0.2, 0.3));
        points.push(Point3::new(0.0, 0.0, -1.0));
        points
    }

    #[test]
    fn an_l_shaped_block_splits_into_parts_that_leave_its_corner_empty() {
        // An L of two 1×1×1 cubes on a 2×1 footprint plus one on top at x 0..1: its hull
        // fills the empty corner (x 1..2, z 1..2); its parts do not.
        // The L's surface as triangles: its outline extruded along y.
        let outline = [
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ];
        let mut vertices = Vec::new();
        for (x, z) in outline {
            vertices.push(Point3::new(x, 0.0, z));
            vertices.push(Point3::new(x, 1.0, z));
        }
        let n = outline.len() as u32;
        let mut triangles = Vec::new();
        for k in 0..n {
            let (a, b) = (2 * k, 2 * ((k + 1) % n));
            triangles.push([a, b, a + 1]);
            triangles.push([b, b + 1, a + 1]);
        }
        // Caps (y = 0 and y = 1): the L as four triangles each.
        for (p, q, r) in [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)] {
            triangles.push([2 * p, 2 * r, 2 * q]);
            triangles.push([2 * p + 1, 2 * q + 1, 2 * r + 1]);
        }
        let parts = convex_parts(&vertices, &triangles);
        assert!(parts.len() >= 2, "{} parts", parts.len());
        // No part reaches far into the empty corner's middle (1.5, ·, 1.5).
        for part in &parts {
            let inside = part.iter().all(|p| p.x <= 1.0 + 0.2 || p.z <= 1.0 + 0.2);
            assert!(inside, "a part fills the corner: {part:?}");
        }
    }

    #[test]
    fn the_hull_of_a_cube_is_its_eight_corners() {
        let mut hull = convex_hull_vertices(&cube_with_inside_points()).unwrap();
        hull.sort_by(|a, b| (a.x, a.y, a.z).partial_cmp(&(b.x, b.y, b.z)).unwrap());
        assert_eq!(hull.len(), 8, "{hull:?}");
        assert!(hull
            .iter()
            .all(|p| p.coords.abs() == nalgebra::Vector3::repeat(1.0)));
    }

    #[test]
    fn a_flat_mesh_keeps_its_own_points() {
        let flat = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
        ];
        let doubled: Vec<_> = flat.iter().chain(&flat).copied().collect();
        let kept = convex_hull_vertices(&doubled).unwrap();
        assert_eq!(kept.len(), 4, "{kept:?}");
        assert!(flat.iter().all(|p| kept.contains(p)), "{kept:?}");
        assert_eq!(convex_hull_vertices(&[]), Err(HullError::Empty));
    }

    #[test]
    fn spreading_a_sphere_keeps_its_lowest_point_and_its_extremes() {
        // 400 points on a unit sphere (a Fibonacci lattice).
        let n = 400;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let sphere: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let a = golden * i as f64;
                Point3::new(r * a.cos(), r * a.sin(), z)
            })
            .collect();
        let spread = spread_points(&sphere, MAX_CONTACT_POINTS);
        assert_eq!(spread.len(), MAX_CONTACT_POINTS);
        let lowest = sphere.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        assert_eq!(spread[0].z, lowest);
        // Every point of the sphere is near a kept one: the kept ones cover it.
        let cover = sphere
            .iter()
            .map(|p| {
                spread
                    .iter()
                    .map(|q| (p - q).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        assert!(cover < 0.8, "largest gap {cover}");
        assert_eq!(
            spread,
            spread_points(&sphere, MAX_CONTACT_POINTS),
            "deterministic"
        );
    }
}
