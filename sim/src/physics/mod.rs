//! Physics: URDF trees stepped at a fixed rate with torque-driven joints, behind one
//! [`World`] trait and two solvers, chosen per robot ([`Solver`]).
//!
//! - [`ArmModel`]: the URDF read into owned `f64` data (limits, efforts, `<dynamics>`,
//!   `<mimic>`, inertials), with forward kinematics of the links and
//!   [`ArmModel::gravity_torques`], our own Jacobian-transpose computation (no rapier), usable
//!   as gravity feed-forward and as an independent reference in tests. Both solvers build on it.
//! - [`World`]: what firmware and robots drive (torques in, joint positions and velocities
//!   out, link poses, a gantry for a floating base); `conformance` (tests) holds both solvers
//!   to the same laws on the shipped URDFs.
//! - [`rapier`]: [`RapierWorld`], rapier3d's multibody (gravity −Z, fixed step, enhanced
//!   determinism), static obstacles and contacts, kinetic friction: the single arms' world.
//! - [`articulated`]: [`articulated::ArticulatedWorld`], our articulated-body solver, the
//!   ground plane and self-collision: robots' world by default.
//! - [`KineticFriction`]: an opt-in split of a joint's dry friction into breakaway (static)
//!   and sliding (kinetic) values, switched by the joint's speed.
//!
//! Joint vectors everywhere have one entry per actuated joint (revolute, continuous,
//! prismatic) in URDF document order, as listed by [`World::joints`]; rad / rad/s / N·m
//! for revolute joints, m / m/s / N for prismatic joints.
//!
//! ```
//! use sim::physics::{RapierWorld, WorldConfig};
//! use sim::piper::kinematics::PIPER_URDF;
//!
//! let mut world = RapierWorld::from_urdf_str(PIPER_URDF, WorldConfig::default())?;
//! let q = [0.0, 1.0, -1.0, 0.0, 0.3, 0.0, 0.0, 0.0];
//! world.set_joint_positions(&q)?;
//! let hold = world.gravity_torques(&q)?; // N·m (N for the fingers)
//! for _ in 0..100 {
//!     world.step(&hold); // 1 ms each
//! }
//! assert!((world.joint_positions()[1] - 1.0).abs() < 1e-3);
//! assert!((world.time_s() - 0.1).abs() < 1e-9);
//! # Ok::<(), sim::physics::PhysicsError>(())
//! ```

mod error;
mod friction;
mod model;
mod obstacle;
mod world;

pub mod articulated;
pub mod rapier;

pub use error::PhysicsError;
pub use friction::KineticFriction;
pub use model::{
    read_urdf, ArmModel, JointInfo, JointKind, LinkInertial, Mimic, DEFAULT_GRAVITY_M_S2,
    MAX_URDF_BYTES,
};
pub use obstacle::{Contact, ObstacleId, ObstacleShape};
pub use rapier::RapierWorld;
pub use world::{Solver, World, WorldConfig};

#[cfg(test)]
mod conformance;
#[cfg(test)]
mod tests;
