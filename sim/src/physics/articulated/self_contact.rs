//! Links touching each other (opt-in): each pair of collision shapes on two links that no
//! joint joins pushes apart through a spring and damper along the contact normal, as the
//! ground does. Shapes are parry3d's (meshes as their convex hulls); the contact query is
//! parry's.

use nalgebra::{Isometry3, Point3, Vector3};
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, SharedShape};

use super::contact::LinkForce;
use crate::description::{CollisionGeometry, CollisionShape};

/// Normal stiffness of a link-on-link contact (N/m): as the ground's per point.
const STIFFNESS_N_M: f64 = 1.0e5;
/// Normal damping (N·s/m).
const DAMPING_N_S_M: f64 = 300.0;

/// One collision shape as parry sees it, on its link.
struct Solid {
    link: usize,
    /// The shape's frame in its link's frame.
    origin: Isometry3<f64>,
    shape: SharedShape,
    /// A sphere holding the shape, in its own frame: centre and radius (m).
    centre: Point3<f64>,
    radius_m: f64,
}

/// The shape pairs that may touch, and the force rule.
pub(super) struct SelfContacts {
    solids: Vec<Solid>,
    /// Each solid's URDF shape (how parry's frame differs from the URDF's).
    kinds: Vec<CollisionShape>,
    /// Pairs of indices into `solids`, on two links no joint joins and not excluded.
    pairs: Vec<(usize, usize)>,
    /// Pairs found touching at the first look: they overlap in the pose the robot starts in
    /// (published meshes of neighbours often do) and are left out for good.
    pruned: bool,
}

impl std::fmt::Debug for SelfContacts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SelfContacts")
            .field("shapes", &self.solids.len())
            .field("pairs", &self.pairs.len())
            .finish()
    }
}

fn solid(shape: &CollisionShape) -> Option<(SharedShape, Point3<f64>, f64)> {
    let f = |x: f64| x as f32;
    Some(match shape {
        CollisionShape::Box { half_m } => (
            SharedShape::new(Cuboid::new(Vector::new(
                f(half_m[0]),
                f(half_m[1]),
                f(half_m[2]),
            ))),
            Point3::origin(),
            Vector3::from(*half_m).norm(),
        ),
        // parry's cylinder stands along y; the URDF's along z: turned in `pose_of`.
        CollisionShape::Cylinder { radius_m, length_m } => (
            SharedShape::new(Cylinder::new(f(length_m / 2.0), f(*radius_m))),
            Point3::origin(),
            radius_m.hypot(length_m / 2.0),
        ),
        CollisionShape::Sphere { radius_m } => (
            SharedShape::new(Ball::new(f(*radius_m))),
            Point3::origin(),
            *radius_m,
        ),
        CollisionShape::Capsule { radius_m, length_m } => (
            SharedShape::new(Capsule::new_z(f(length_m / 2.0), f(*radius_m))),
            Point3::origin(),
            radius_m + length_m / 2.0,
        ),
        CollisionShape::Hull { points_m, parts_m } => {
            let convex = |points: &[Point3<f64>]| {
                let points: Vec<Vector> = points
                    .iter()
                    .map(|p| Vector::new(f(p.x), f(p.y), f(p.z)))
                    .collect();
                ConvexPolyhedron::from_convex_hull(&points)
            };
            let shape = if parts_m.is_empty() {
                // Its hull through the contact points (at most 16): coarse for a rounded
                // mesh; `convex_decomposition` gives the parts' full hulls.
                SharedShape::new(convex(points_m)?)
            } else {
                let parts: Vec<(Pose, SharedShape)> = parts_m
                    .iter()
                    .filter_map(|part| Some((Pose::IDENTITY, SharedShape::new(convex(part)?))))
                    .collect();
                if parts.is_empty() {
                    return None;
                }
                SharedShape::compound(parts)
            };
            let all: Vec<&Point3<f64>> = points_m.iter().chain(parts_m.iter().flatten()).collect();
            let n = all.len().max(1) as f64;
            let centre = Point3::from(all.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n);
            let radius = all.iter().map(|p| (*p - centre).norm()).fold(0.0, f64::max);
            (shape, centre, radius)
        }
    })
}

/// parry's pose of a shape whose frame is `frame` in the world (cylinders turned onto z).
fn pose_of(frame: &Isometry3<f64>, shape: &CollisionShape) -> Pose {
    let frame = match shape {
        CollisionShape::Cylinder { .. } => {
            frame
                * nalgebra::UnitQuaternion::from_euler_angles(std::f64::consts::FRAC_PI_2, 0.0, 0.0)
        }
        _ => *frame,
    };
    let t = frame.translation.vector;
    let q = frame.rotation;
    Pose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32),
    )
}

impl SelfContacts {
    /// The pairs of `geometry`'s shapes on links that no joint joins (`joined(a, b)`) and
    /// that `excluded(a, b)` does not leave out (link indices, URDF order).
    pub(super) fn new(
        geometry: &CollisionGeometry,
        joined: impl Fn(usize, usize) -> bool,
        excluded: impl Fn(usize, usize) -> bool,
    ) -> Self {
        let solids: Vec<(Solid, CollisionShape)> = geometry
            .shapes
            .iter()
            .filter_map(|s| {
                let (shape, centre, radius_m) = solid(&s.shape)?;
                Some((
                    Solid {
                        link: s.link,
                        origin: s.origin,
                        shape,
                        centre,
                        radius_m,
                    },
                    s.shape.clone(),
                ))
            })
            .collect();
        let mut pairs = Vec::new();
        for a in 0..solids.len() {
            for b in a + 1..solids.len() {
                let (la, lb) = (solids[a].0.link, solids[b].0.link);
                if la != lb && !joined(la, lb) && !excluded(la, lb) {
                    pairs.push((a, b));
                }
            }
        }
        Self {
            kinds: solids.iter().map(|(_, k)| k.clone()).collect(),
            solids: solids.into_iter().map(|(s, _)| s).collect(),
            pairs,
            pruned: false,
        }
    }

    /// How many shape pairs are watched.
    pub(super) fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// The forces of every touching pair with the links at `poses`, each point moving as
    /// `velocity_of(link, point)` says; both links get theirs (equal and opposite).
    pub(super) fn forces(
        &mut self,
        poses: &[Isometry3<f64>],
        velocity_of: impl Fn(usize, &Vector3<f64>) -> Vector3<f64>,
    ) -> Vec<LinkForce> {
        let frames: Vec<Isometry3<f64>> = self
            .solids
            .iter()
            .map(|s| poses[s.link] * s.origin)
            .collect();
        let mut touching = Vec::new();
        let mut out = Vec::new();
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            let (sa, sb) = (&self.solids[a], &self.solids[b]);
            let gap = (frames[a] * sa.centre - frames[b] * sb.centre).norm();
            if gap > sa.radius_m + sb.radius_m {
                continue;
            }
            let (pa, pb) = (
                pose_of(&frames[a], &self.kinds[a]),
                pose_of(&frames[b], &self.kinds[b]),
            );
            let Ok(Some(contact)) =
                parry3d::query::contact(&pa, sa.shape.as_ref(), &pb, sb.shape.as_ref(), 0.0)
            else {
                continue;
            };
            if contact.dist >= 0.0 {
                continue;
            }
            touching.push(k);
            if !self.pruned {
                continue;
            }
            let v = |p: parry3d::math::Vector| {
                Vector3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z))
            };
            let (point_a, point_b, normal) =
                (v(contact.point1), v(contact.point2), v(contact.normal1));
            let depth = -f64::from(contact.dist);
            // Speed of b's point towards a's along the normal (positive: closing).
            let closing =
                (velocity_of(sa.link, &point_a) - velocity_of(sb.link, &point_b)).dot(&normal);
            let push = (STIFFNESS_N_M * depth + DAMPING_N_S_M * closing).max(0.0);
            out.push(LinkForce {
                link: sb.link,
                at_m: point_b,
                force_n: normal * push,
            });
            out.push(LinkForce {
                link: sa.link,
                at_m: point_a,
                force_n: -normal * push,
            });
        }
        if !self.pruned {
            // What overlaps as the robot starts is how it is built, not a collision.
            if !touching.is_empty() {
                tracing::info!(
                    pairs = touching.len(),
                    "self-collision: shape pairs that overlap at the start are left out"
                );
            }
            let mut k = 0;
            self.pairs.retain(|_| {
                let keep = !touching.contains(&k);
                k += 1;
                keep
            });
            self.pruned = true;
        }
        out
    }
}
