//! Static obstacles placed in the world and the contacts the arm makes with them.

/// Shape of a static obstacle. Dimensions in metres; cylinders stand along world Z (URDF
/// convention), unlike rapier's Y-up cylinders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ObstacleShape {
    /// Axis-aligned box given by its half extents along X, Y, Z.
    Box {
        /// Half extents, m.
        half_extents_m: [f64; 3],
    },
    /// Sphere.
    Sphere {
        /// Radius, m.
        radius_m: f64,
    },
    /// Cylinder whose axis is world Z.
    Cylinder {
        /// Radius, m.
        radius_m: f64,
        /// Half of the height along Z, m.
        half_height_m: f64,
    },
}

/// Identifier of an obstacle, unique for the lifetime of its world (never reused).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ObstacleId(pub u64);

/// An arm link touching an obstacle.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// URDF name of the arm link.
    pub link: String,
    /// The obstacle touched.
    pub obstacle: ObstacleId,
    /// Deepest penetration of the link into the obstacle during the last step, m (≥ 0; 0 when
    /// the shapes only touch within rapier's contact margin).
    pub penetration_m: f64,
    /// Normal contact force estimate: total contact impulse of the last step divided by the
    /// step length, N.
    pub normal_force_n: f64,
}
