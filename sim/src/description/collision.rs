//! Each link's collision geometry as the physics uses it: primitives as the URDF gives them,
//! meshes as the contact points of their convex hulls.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

use super::hull::contact_points;
use super::mesh::MeshCache;
use super::{Description, DescriptionError};

/// What to do with a collision mesh that cannot be found or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MissingMeshes {
    /// Refuse the robot, naming the mesh and every place searched (the default).
    #[default]
    Refuse,
    /// Go on without that collision shape, with a warning naming it.
    Skip,
}

/// One collision shape of a link, in the link's frame.
#[derive(Debug, Clone, PartialEq)]
pub enum CollisionShape {
    /// A box of half extents (m).
    Box {
        /// Half extents along x, y, z (m).
        half_m: [f64; 3],
    },
    /// A cylinder along z (m).
    Cylinder {
        /// Radius (m).
        radius_m: f64,
        /// Length (m).
        length_m: f64,
    },
    /// A sphere (m).
    Sphere {
        /// Radius (m).
        radius_m: f64,
    },
    /// A capsule along z: a cylinder with hemispherical ends (m).
    Capsule {
        /// Radius (m).
        radius_m: f64,
        /// Length of the cylinder between the ends' centres (m).
        length_m: f64,
    },
    /// A mesh: the contact points of its convex hull (scaled, m), and, when the robot asks
    /// for it, its convex decomposition (each part's hull vertices): what a link meets other
    /// links with. The ground meets only the lowest points of a body, which are its hull's,
    /// so it needs no parts.
    Hull {
        /// The points.
        points_m: Vec<Point3<f64>>,
        /// The convex parts (empty: the whole hull is one).
        parts_m: Vec<Vec<Point3<f64>>>,
    },
}

/// A collision shape placed on its link.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkShape {
    /// The link (URDF link index).
    pub link: usize,
    /// The shape's frame in the link's frame (`<collision><origin>`).
    pub origin: Isometry3<f64>,
    /// The shape.
    pub shape: CollisionShape,
}

impl LinkShape {
    /// The height (m) of the shape's lowest point when its link is at `link_pose` in the
    /// world: where it would first meet a floor at z = 0. A point `p` of the shape's frame is
    /// at `t.z + R[2,·]·p`; a disc of radius r normal to the frame's z axis reaches
    /// r·sin(tilt) below its centre.
    pub fn lowest_z_m(&self, link_pose: &Isometry3<f64>) -> f64 {
        let frame = link_pose * self.origin;
        let centre_z = frame.translation.vector.z;
        let rotation = frame.rotation.to_rotation_matrix();
        let row = |c: usize| rotation.matrix()[(2, c)];
        let reach = |c: usize, half: f64| row(c).abs() * half;
        let rim = |r: f64| r * (1.0 - row(2) * row(2)).max(0.0).sqrt();
        match &self.shape {
            CollisionShape::Box { half_m } => {
                centre_z - reach(0, half_m[0]) - reach(1, half_m[1]) - reach(2, half_m[2])
            }
            CollisionShape::Cylinder { radius_m, length_m } => {
                centre_z - reach(2, length_m / 2.0) - rim(*radius_m)
            }
            CollisionShape::Sphere { radius_m } => centre_z - radius_m,
            CollisionShape::Capsule { radius_m, length_m } => {
                centre_z - reach(2, length_m / 2.0) - radius_m
            }
            CollisionShape::Hull { points_m, .. } => points_m
                .iter()
                .map(|p| (frame * p).z)
                .fold(f64::INFINITY, f64::min),
        }
    }
}

/// Every link's collision shapes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CollisionGeometry {
    /// The shapes, links in URDF order.
    pub shapes: Vec<LinkShape>,
    /// Meshes left out ([`MissingMeshes::Skip`]): one line each, for the user.
    pub skipped: Vec<String>,
}

impl CollisionGeometry {
    /// The lowest point of every shape with its links at `poses` (URDF link order): the
    /// shape's link and the point's height (m), shape by shape.
    pub fn lowest_points(&self, poses: &[Isometry3<f64>]) -> Vec<(usize, f64)> {
        self.shapes
            .iter()
            .map(|s| (s.link, s.lowest_z_m(&poses[s.link])))
            .collect()
    }

    /// The lowest of [`CollisionGeometry::lowest_points`]: its link and height (m).
    pub fn lowest_point(&self, poses: &[Isometry3<f64>]) -> Option<(usize, f64)> {
        self.lowest_points(poses)
            .into_iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// A mesh's hull contact points and its convex parts (each part's hull vertices).
type HullAndParts = (Vec<Point3<f64>>, Vec<Vec<Point3<f64>>>);

/// The frame of a URDF `<origin>`.
pub fn isometry(pose: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = pose.xyz.0;
    let [roll, pitch, yaw] = pose.rpy.0;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

impl Description {
    /// Every link's collision shapes, meshes read and hulled (each file once).
    pub fn collision_geometry(
        &self,
        missing: MissingMeshes,
    ) -> Result<CollisionGeometry, DescriptionError> {
        self.collision_geometry_decomposed(missing, &[])
    }

    /// As [`Description::collision_geometry`], the meshes of the links named in `decompose`
    /// also split into convex parts (parry3d's V-HACD; seconds for a large mesh).
    pub fn collision_geometry_decomposed(
        &self,
        missing: MissingMeshes,
        decompose: &[String],
    ) -> Result<CollisionGeometry, DescriptionError> {
        let mut cache = MeshCache::default();
        let mut geometry = CollisionGeometry::default();
        for (link, l) in self.robot().links.iter().enumerate() {
            for collision in &l.collision {
                let origin = isometry(&collision.origin);
                let shape = match &collision.geometry {
                    urdf_rs::Geometry::Box { size } => CollisionShape::Box {
                        half_m: size.0.map(|s| s / 2.0),
                    },
                    urdf_rs::Geometry::Cylinder { radius, length } => CollisionShape::Cylinder {
                        radius_m: *radius,
                        length_m: *length,
                    },
                    urdf_rs::Geometry::Capsule { radius, length } => CollisionShape::Capsule {
                        radius_m: *radius,
                        length_m: *length,
                    },
                    urdf_rs::Geometry::Sphere { radius } => {
                        CollisionShape::Sphere { radius_m: *radius }
                    }
                    urdf_rs::Geometry::Mesh { filename, scale } => {
                        let scale = scale.as_ref().map_or([1.0; 3], |s| s.0);
                        let parts = decompose.contains(&l.name);
                        match self.mesh_hull(&mut cache, filename, scale, parts) {
                            Ok((points_m, parts_m)) => CollisionShape::Hull { points_m, parts_m },
                            Err(problem) if missing == MissingMeshes::Skip => {
                                geometry.skipped.push(format!(
                                    "link `{}`: collision mesh left out: {}",
                                    l.name, problem.message
                                ));
                                continue;
                            }
                            Err(problem) => {
                                return Err(DescriptionError::at(
                                    problem.line,
                                    format!(
                                        "link `{}`'s collision mesh: {}",
                                        l.name, problem.message
                                    ),
                                ))
                            }
                        }
                    }
                };
                geometry.shapes.push(LinkShape {
                    link,
                    origin,
                    shape,
                });
            }
        }
        Ok(geometry)
    }

    /// The hull contact points of the mesh `uri`, scaled, and its convex parts if `parts`.
    fn mesh_hull(
        &self,
        cache: &mut MeshCache,
        uri: &str,
        scale: [f64; 3],
        parts: bool,
    ) -> Result<HullAndParts, DescriptionError> {
        let line = self.line_mentioning(uri);
        let fail = |message: String| DescriptionError::at(line, message);
        let path = self.paths().resolve(uri).map_err(|e| fail(e.to_string()))?;
        let points = cache.points(&path).map_err(|e| fail(e.to_string()))?;
        let scaled = |p: &Point3<f64>| Point3::new(p.x * scale[0], p.y * scale[1], p.z * scale[2]);
        let hull: Vec<Point3<f64>> = points.iter().map(scaled).collect();
        let contact = contact_points(&hull).map_err(|e| fail(format!("`{uri}`: {e}")))?;
        if !parts {
            return Ok((contact, Vec::new()));
        }
        let mesh = super::visual::read_mesh_triangles(&path).map_err(|e| fail(e.to_string()))?;
        let vertices: Vec<Point3<f64>> = mesh
            .vertices
            .iter()
            .map(|v| {
                scaled(&Point3::new(
                    f64::from(v[0]),
                    f64::from(v[1]),
                    f64::from(v[2]),
                ))
            })
            .collect();
        Ok((
            contact,
            super::hull::convex_parts(&vertices, &mesh.triangles),
        ))
    }
}
