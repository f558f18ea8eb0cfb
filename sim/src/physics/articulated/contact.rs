//! Ground contact for the articulated-body solver: a link's collision shapes (primitives,
//! and meshes as their hulls' contact points) touching the plane z = 0 through springs and
//! dampers (normal) and anchored springs capped by Coulomb's law (tangential), so a foot at
//! rest stays where it stands.

use nalgebra::{Isometry3, Point3, Vector3};

use crate::description::{CollisionGeometry, CollisionShape};

/// Normal stiffness of one contact point (N/m): 40 kg on eight foot corners sink ~0.5 mm.
const NORMAL_STIFFNESS_N_M: f64 = 1.0e5;
/// Normal damping of one contact point (N·s/m): a foot lands without bouncing, and the
/// explicit force stays stable with a link of 1 kg at a 0.5 ms substep.
const NORMAL_DAMPING_N_S_M: f64 = 300.0;
/// Stiffness of the tangential anchor spring (N/m).
const TANGENT_STIFFNESS_N_M: f64 = 1.0e5;
/// Damping of the tangential spring (N·s/m).
const TANGENT_DAMPING_N_S_M: f64 = 300.0;
/// Points drawn on each rim of a cylinder.
const CYLINDER_RIM_POINTS: usize = 8;

/// One place of a link that can touch the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Feature {
    /// A corner or rim point, in the link frame.
    Point(Point3<f64>),
    /// A sphere (a sphere, a capsule's end), centre in the link frame and radius.
    Sphere(Point3<f64>, f64),
}

/// A link's contact features and the anchors of the ones touching.
#[derive(Debug, Clone)]
pub(super) struct GroundContacts {
    /// Per feature: its link and shape.
    features: Vec<(usize, Feature)>,
    /// Per run of one link's features, the sphere that holds them.
    bounds: Vec<Bound>,
    /// Per feature, where its tangential spring is anchored on the ground (x, y), while it
    /// touches.
    anchors: Vec<Option<[f64; 2]>>,
    /// Friction coefficient between every link and the ground.
    friction: f64,
}

/// A force on a link, in the world: what touching the ground does to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LinkForce {
    /// The link.
    pub link: usize,
    /// Where the force acts (world, m).
    pub at_m: Vector3<f64>,
    /// The force (world, N).
    pub force_n: Vector3<f64>,
}

fn features_of(shape: &CollisionShape, origin: &Isometry3<f64>) -> Vec<Feature> {
    let at = |x: f64, y: f64, z: f64| origin * Point3::new(x, y, z);
    match shape {
        CollisionShape::Box {
            half_m: [hx, hy, hz],
        } => {
            let mut corners = Vec::with_capacity(8);
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    for sz in [-1.0, 1.0] {
                        corners.push(Feature::Point(at(sx * hx, sy * hy, sz * hz)));
                    }
                }
            }
            corners
        }
        CollisionShape::Cylinder { radius_m, length_m } => {
            let mut rims = Vec::with_capacity(2 * CYLINDER_RIM_POINTS);
            for z in [-length_m / 2.0, length_m / 2.0] {
                for k in 0..CYLINDER_RIM_POINTS {
                    let angle = std::f64::consts::TAU * k as f64 / CYLINDER_RIM_POINTS as f64;
                    rims.push(Feature::Point(at(
                        radius_m * angle.cos(),
                        radius_m * angle.sin(),
                        z,
                    )));
                }
            }
            rims
        }
        CollisionShape::Capsule { radius_m, length_m } => vec![
            Feature::Sphere(at(0.0, 0.0, -length_m / 2.0), *radius_m),
            Feature::Sphere(at(0.0, 0.0, length_m / 2.0), *radius_m),
        ],
        CollisionShape::Sphere { radius_m } => {
            vec![Feature::Sphere(at(0.0, 0.0, 0.0), *radius_m)]
        }
        CollisionShape::Hull { points_m, .. } => points_m
            .iter()
            .map(|p| Feature::Point(origin * p))
            .collect(),
    }
}

/// A sphere in a link's frame that holds all of its features: a link whose sphere is above
/// the ground has no feature touching it, and its features are not looked at.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bound {
    link: usize,
    centre: Point3<f64>,
    radius_m: f64,
    /// Its features: `features[first..end]`.
    first: usize,
    end: usize,
}

impl GroundContacts {
    /// The contact features of every link's collision shapes (link indices in URDF order).
    pub(super) fn new(geometry: &CollisionGeometry, friction: f64) -> Self {
        let mut features: Vec<(usize, Feature)> = Vec::new();
        let mut bounds: Vec<Bound> = Vec::new();
        // Shapes come link by link (URDF order); a link's features stay together.
        for shape in &geometry.shapes {
            let first = features.len();
            features.extend(
                features_of(&shape.shape, &shape.origin)
                    .into_iter()
                    .map(|f| (shape.link, f)),
            );
            match bounds.last_mut() {
                Some(b) if b.link == shape.link => b.end = features.len(),
                _ => bounds.push(Bound {
                    link: shape.link,
                    centre: Point3::origin(),
                    radius_m: 0.0,
                    first,
                    end: features.len(),
                }),
            }
        }
        for b in &mut bounds {
            let points: Vec<(Point3<f64>, f64)> = features[b.first..b.end]
                .iter()
                .map(|(_, f)| match f {
                    Feature::Point(p) => (*p, 0.0),
                    Feature::Sphere(c, r) => (*c, *r),
                })
                .collect();
            let n = points.len().max(1) as f64;
            let sum: Vector3<f64> = points.iter().map(|(p, _)| p.coords).sum();
            let centre = Point3::from(sum / n);
            b.centre = centre;
            b.radius_m = points
                .iter()
                .map(|(p, r)| (p - centre).norm() + r)
                .fold(0.0, f64::max);
        }
        let anchors = vec![None; features.len()];
        Self {
            features,
            bounds,
            anchors,
            friction,
        }
    }

    /// The ground's forces on the links at their world poses `poses`, each point moving as
    /// `velocity_of(link, point)` says (world, m/s). Updates the anchors: a feature that
    /// leaves the ground forgets its own, one that slides drags it along.
    pub(super) fn forces(
        &mut self,
        poses: &[Isometry3<f64>],
        velocity_of: impl Fn(usize, &Vector3<f64>) -> Vector3<f64>,
    ) -> Vec<LinkForce> {
        let mut out = Vec::new();
        for bound in &self.bounds {
            let centre_z = (poses[bound.link] * bound.centre).z;
            let range = bound.first..bound.end;
            if centre_z > bound.radius_m {
                self.anchors[range].fill(None);
                continue;
            }
            let features = &self.features[range.clone()];
            let anchors = &mut self.anchors[range];
            Self::touching(
                features,
                anchors,
                self.friction,
                poses,
                &velocity_of,
                &mut out,
            );
        }
        out
    }

    /// The forces of the features of one link that may touch the ground.
    fn touching(
        features: &[(usize, Feature)],
        anchors: &mut [Option<[f64; 2]>],
        friction: f64,
        poses: &[Isometry3<f64>],
        velocity_of: &impl Fn(usize, &Vector3<f64>) -> Vector3<f64>,
        out: &mut Vec<LinkForce>,
    ) {
        for ((link, feature), anchor) in features.iter().zip(anchors) {
            let (point, depth) = match feature {
                Feature::Point(p) => {
                    let w = (poses[*link] * p).coords;
                    (w, -w.z)
                }
                Feature::Sphere(c, r) => {
                    let w = (poses[*link] * c).coords;
                    (Vector3::new(w.x, w.y, w.z - r), r - w.z)
                }
            };
            if depth <= 0.0 {
                *anchor = None;
                continue;
            }
            let v = velocity_of(*link, &point);
            let normal = (NORMAL_STIFFNESS_N_M * depth - NORMAL_DAMPING_N_S_M * v.z).max(0.0);
            let a = anchor.get_or_insert([point.x, point.y]);
            let stretch = [point.x - a[0], point.y - a[1]];
            let mut tangent = [
                -TANGENT_STIFFNESS_N_M * stretch[0] - TANGENT_DAMPING_N_S_M * v.x,
                -TANGENT_STIFFNESS_N_M * stretch[1] - TANGENT_DAMPING_N_S_M * v.y,
            ];
            let limit = friction * normal;
            let size = tangent[0].hypot(tangent[1]);
            if size > limit {
                // Sliding: the force is Coulomb's, and the anchor moves with the foot so that
                // its spring alone would pull that hard.
                let scale = if size > 0.0 { limit / size } else { 0.0 };
                tangent = [tangent[0] * scale, tangent[1] * scale];
                *a = [
                    point.x + tangent[0] / TANGENT_STIFFNESS_N_M,
                    point.y + tangent[1] / TANGENT_STIFFNESS_N_M,
                ];
            }
            out.push(LinkForce {
                link: *link,
                at_m: point,
                force_n: Vector3::new(tangent[0], tangent[1], normal),
            });
        }
    }
}
