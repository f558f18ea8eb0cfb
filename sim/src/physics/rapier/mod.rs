//! rapier3d's multibody as a [`crate::physics::World`]: one URDF tree as a reduced-coordinate
//! multibody (rapier3d-urdf's bodies and joints), static obstacles and contacts with them,
//! kinetic friction. The Piper's, the Realman's and the RobStride rigs' worlds; a robot file
//! chooses it with `physics: rapier`.

mod world;

pub use world::RapierWorld;
