//! A URDF tree stepped by our own articulated-body solver: `O(links)` per step where rapier's
//! multibody builds and factors a dense mass matrix (`O(links · dofs²)`), for robots whose
//! joints are many (a 20-actuator humanoid).
//!
//! - [`ArticulatedWorld`]: Featherstone's articulated-body algorithm (three passes over the
//!   tree) for a fixed or free root, joint torques, armature, damping and friction treated
//!   implicitly, stops at the limits; the ground as springs at the links' collision
//!   primitives with anchored friction.
//! - `spatial`: the 6D vector algebra it is written in.

mod contact;
mod self_contact;
mod spatial;
mod world;

pub use world::{ArticulatedWorld, SUBSTEPS};

#[cfg(test)]
mod tests;
