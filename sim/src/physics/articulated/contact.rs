//! Ground contact for the articulated-body solver: a link's URDF collision primitives
//! touching the plane z = 0 through springs and dampers (normal) and anchored springs capped
//! by Coulomb's law (tangential), so a foot at rest stays where it stands.

use nalgebra::{Isometry3, Point3, Vector3};

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

fn features_of(geometry: &urdf_rs::Geometry, origin: &Isometry3<f64>) -> Vec<Feature> {
    let at = |x: f64, y: f64, z: f64| origin * Point3::new(x, y, z);
    match geometry {
        urdf_rs::Geometry::Box { size } => {
            let [hx, hy, hz] = size.0.map(|s| s / 2.0);
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
        urdf_rs::Geometry::Cylinder { radius, length } => {
            let mut rims = Vec::with_capacity(2 * CYLINDER_RIM_POINTS);
            for z in [-length / 2.0, length / 2.0] {
                for k in 0..CYLINDER_RIM_POINTS {
                    let angle = std::f64::consts::TAU * k as f64 / CYLINDER_RIM_POINTS as f64;
                    rims.push(Feature::Point(at(
                        radius * angle.cos(),
                        radius * angle.sin(),
                        z,
                    )));
                }
            }
            rims
        }
        urdf_rs::Geometry::Capsule { radius, length } => vec![
            Feature::Sphere(at(0.0, 0.0, -length / 2.0), *radius),
            Feature::Sphere(at(0.0, 0.0, length / 2.0), *radius),
        ],
        urdf_rs::Geometry::Sphere { radius } => vec![Feature::Sphere(at(0.0, 0.0, 0.0), *radius)],
        // Meshes are not read (as in the rapier world).
        urdf_rs::Geometry::Mesh { .. } => Vec::new(),
    }
}

fn isometry(pose: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = pose.xyz.0;
    let [r, p, w] = pose.rpy.0;
    Isometry3::from_parts(
        nalgebra::Translation3::new(x, y, z),
        nalgebra::UnitQuaternion::from_euler_angles(r, p, w),
    )
}

impl GroundContacts {
    /// The contact features of every link of `robot` (link indices in URDF order).
    pub(super) fn new(robot: &urdf_rs::Robot, friction: f64) -> Self {
        let mut features = Vec::new();
        for (link, l) in robot.links.iter().enumerate() {
            for collision in &l.collision {
                let origin = isometry(&collision.origin);
                features.extend(
                    features_of(&collision.geometry, &origin)
                        .into_iter()
                        .map(|f| (link, f)),
                );
            }
        }
        let anchors = vec![None; features.len()];
        Self {
            features,
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
        for ((link, feature), anchor) in self.features.iter().zip(&mut self.anchors) {
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
            let limit = self.friction * normal;
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
        out
    }
}
