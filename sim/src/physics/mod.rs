//! Physics world: URDF models in rapier3d, stepped at a fixed rate with torque-driven joints.
//!
//! - [`ArmModel`]: the URDF read into owned `f64` data (limits, efforts, `<dynamics>`,
//!   `<mimic>`, inertials), with forward kinematics of the links and
//!   [`ArmModel::gravity_torques`], our own Jacobian-transpose computation (no rapier).
//! - [`ArmWorld`]: a fixed-base articulated world (rapier3d multibody) loaded from a URDF:
//!   motor torques in, joint positions and velocities out, static obstacles and contacts.

mod error;
mod model;

pub use error::PhysicsError;
pub use model::{ArmModel, JointInfo, JointKind, LinkInertial, Mimic, DEFAULT_GRAVITY_M_S2};
mod obstacle;
mod world;

pub use obstacle::{Contact, ObstacleId, ObstacleShape};
pub use world::{ArmWorld, WorldConfig};

#[cfg(test)]
mod tests;
