//! What a physics world is, whichever solver steps it: the [`World`] trait the firmware and
//! robots drive, the [`Solver`]s that implement it and the [`WorldConfig`] both take.

use nalgebra::Isometry3;

use super::articulated::ArticulatedWorld;
use super::model::{ArmModel, JointInfo, DEFAULT_GRAVITY_M_S2};
use super::rapier::RapierWorld;
use super::PhysicsError;
use crate::description::{CollisionGeometry, Description};

/// Configuration of a world, for every [`Solver`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldConfig {
    /// Length of one [`World::step`], s. Default 0.001 (1 kHz).
    pub step_s: f64,
    /// Gravity in the URDF base frame, m/s². Default `[0, 0, −9.81]` (URDF is Z-up).
    pub gravity_m_s2: [f64; 3],
    /// `None` (default): the URDF root link is fixed to the world at the origin. `Some(h)`:
    /// the root link is a free body whose origin starts `h` m above the world origin (a
    /// legged robot; give a [`RapierWorld`] ground to stand on with
    /// [`RapierWorld::add_obstacle`], an [`ArticulatedWorld`] has the plane z = 0).
    pub floating_base_height_m: Option<f64>,
}

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            step_s: 0.001,
            gravity_m_s2: DEFAULT_GRAVITY_M_S2,
            floating_base_height_m: None,
        }
    }
}

/// Which solver steps a world.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Solver {
    /// Our articulated-body solver ([`ArticulatedWorld`]): `O(links)` per step, the ground
    /// plane, self-collision on request. The default for robots.
    #[default]
    Articulated,
    /// rapier3d's multibody ([`RapierWorld`]): a dense mass matrix per step, obstacles and
    /// contacts with them, kinetic friction. The single arms' world.
    Rapier,
}

impl Solver {
    /// Every solver, in the order messages list them.
    pub const ALL: [Self; 2] = [Self::Articulated, Self::Rapier];

    /// Its word in robot files (`physics: articulated`).
    pub fn word(self) -> &'static str {
        match self {
            Self::Articulated => "articulated",
            Self::Rapier => "rapier",
        }
    }

    /// The solver a word names (`articulated`, `rapier`).
    pub fn parse(word: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.word() == word)
    }

    /// A world of this solver for a checked URDF and its collision geometry.
    pub fn load(
        self,
        description: &Description,
        geometry: &CollisionGeometry,
        config: WorldConfig,
    ) -> Result<Box<dyn World>, PhysicsError> {
        Ok(match self {
            Self::Articulated => Box::new(ArticulatedWorld::from_description(
                description,
                geometry,
                config,
            )?),
            Self::Rapier => Box::new(RapierWorld::from_description(
                description,
                geometry,
                config,
            )?),
        })
    }
}

/// A URDF tree stepped in fixed time steps with torques at its joints: what a robot's
/// firmware needs of physics, whichever [`Solver`] computes it.
///
/// Joint vectors have one entry per actuated joint (revolute, continuous, prismatic) in URDF
/// document order, as [`World::joints`] lists them; rad, rad/s and N·m for revolute joints,
/// m, m/s and N for prismatic ones. Both solvers obey the laws of
/// `physics::conformance` (its tests): the model's gravity torques hold the tree still, a
/// joint without damping or friction keeps its energy, joints stop at their limits, mimic
/// followers follow, a free tree falls at g.
pub trait World: Send + std::fmt::Debug {
    /// The solver computing this world.
    fn solver(&self) -> Solver;

    /// The model (kinematics, inertials, limits).
    fn model(&self) -> &ArmModel;

    /// The actuated joints, in URDF document order.
    fn joints(&self) -> &[JointInfo] {
        self.model().joints()
    }

    /// Index of the actuated joint called `name`.
    fn joint_index(&self, name: &str) -> Option<usize> {
        self.model().joint_index(name)
    }

    /// Sets joint `joint`'s armature (reflected rotor inertia, kg·m² or kg).
    fn set_armature(&mut self, joint: usize, armature: f64);

    /// Places the joints at `q` at rest (clamped to their limits).
    fn set_joint_positions(&mut self, q: &[f64]) -> Result<(), PhysicsError>;

    /// Disturbance torques (N·m, N) added to every step's motor torques until changed.
    fn set_external_joint_torques(&mut self, tau: &[f64]);

    /// One step of [`WorldConfig::step_s`] with motor torques `joint_torques` (missing
    /// entries 0).
    fn step(&mut self, joint_torques: &[f64]);

    /// `Err` naming the first joint whose state stopped being finite, and when.
    fn check_finite(&self) -> Result<(), PhysicsError>;

    /// Joint positions (rad, m).
    fn joint_positions(&self) -> Vec<f64>;

    /// Joint velocities (rad/s, m/s).
    fn joint_velocities(&self) -> Vec<f64>;

    /// Pose of link `link` in the world, if the URDF has it.
    fn link_pose(&self, link: &str) -> Option<Isometry3<f64>>;

    /// Simulated time since the world was built (s).
    fn time_s(&self) -> f64;

    /// Steps taken since the world was built.
    fn steps(&self) -> u64;

    /// Each joint's inertia with the others held, at the current pose (the mass matrix's
    /// diagonal, armature included; kg·m² or kg).
    fn mass_matrix_diagonal(&self) -> Vec<f64>;

    /// Holds a floating root where it is (a stand takes its weight) or lets it go from rest.
    /// A solver that cannot hold a root refuses with [`PhysicsError::Unsupported`].
    fn set_root_held(&mut self, held: bool) -> Result<(), PhysicsError>;

    /// Whether a stand holds the root.
    fn root_held(&self) -> bool;
}

impl World for ArticulatedWorld {
    fn solver(&self) -> Solver {
        Solver::Articulated
    }
    fn model(&self) -> &ArmModel {
        ArticulatedWorld::model(self)
    }
    fn set_armature(&mut self, joint: usize, armature: f64) {
        ArticulatedWorld::set_armature(self, joint, armature);
    }
    fn set_joint_positions(&mut self, q: &[f64]) -> Result<(), PhysicsError> {
        ArticulatedWorld::set_joint_positions(self, q)
    }
    fn set_external_joint_torques(&mut self, tau: &[f64]) {
        ArticulatedWorld::set_external_joint_torques(self, tau);
    }
    fn step(&mut self, joint_torques: &[f64]) {
        ArticulatedWorld::step(self, joint_torques);
    }
    fn check_finite(&self) -> Result<(), PhysicsError> {
        ArticulatedWorld::check_finite(self)
    }
    fn joint_positions(&self) -> Vec<f64> {
        ArticulatedWorld::joint_positions(self)
    }
    fn joint_velocities(&self) -> Vec<f64> {
        ArticulatedWorld::joint_velocities(self)
    }
    fn link_pose(&self, link: &str) -> Option<Isometry3<f64>> {
        ArticulatedWorld::link_pose(self, link)
    }
    fn time_s(&self) -> f64 {
        ArticulatedWorld::time_s(self)
    }
    fn steps(&self) -> u64 {
        ArticulatedWorld::steps(self)
    }
    fn mass_matrix_diagonal(&self) -> Vec<f64> {
        ArticulatedWorld::mass_matrix_diagonal(self)
    }
    fn set_root_held(&mut self, held: bool) -> Result<(), PhysicsError> {
        ArticulatedWorld::set_root_held(self, held);
        Ok(())
    }
    fn root_held(&self) -> bool {
        ArticulatedWorld::root_held(self)
    }
}

impl World for RapierWorld {
    fn solver(&self) -> Solver {
        Solver::Rapier
    }
    fn model(&self) -> &ArmModel {
        RapierWorld::model(self)
    }
    fn set_armature(&mut self, joint: usize, armature: f64) {
        RapierWorld::set_armature(self, joint, armature);
    }
    fn set_joint_positions(&mut self, q: &[f64]) -> Result<(), PhysicsError> {
        RapierWorld::set_joint_positions(self, q)
    }
    fn set_external_joint_torques(&mut self, tau: &[f64]) {
        RapierWorld::set_external_joint_torques(self, tau);
    }
    fn step(&mut self, joint_torques: &[f64]) {
        RapierWorld::step(self, joint_torques);
    }
    fn check_finite(&self) -> Result<(), PhysicsError> {
        RapierWorld::check_finite(self)
    }
    fn joint_positions(&self) -> Vec<f64> {
        RapierWorld::joint_positions(self)
    }
    fn joint_velocities(&self) -> Vec<f64> {
        RapierWorld::joint_velocities(self)
    }
    fn link_pose(&self, link: &str) -> Option<Isometry3<f64>> {
        RapierWorld::link_pose(self, link)
    }
    fn time_s(&self) -> f64 {
        RapierWorld::time_s(self)
    }
    fn steps(&self) -> u64 {
        RapierWorld::steps(self)
    }
    fn mass_matrix_diagonal(&self) -> Vec<f64> {
        // The model's composite-inertia diagonal at the world's pose: a fixed base's exactly,
        // a floating one's with the base held (what a joint's own loop sees standing).
        let q = RapierWorld::joint_positions(self);
        self.model()
            .mass_matrix_diagonal(&q)
            .unwrap_or_else(|_| vec![0.0; q.len()])
    }
    fn set_root_held(&mut self, held: bool) -> Result<(), PhysicsError> {
        if held {
            // rapier's multibody root is fixed or free when the world is built; holding and
            // letting go of it mid-run is the articulated solver's (a robot's gantry).
            return Err(PhysicsError::Unsupported {
                what: "holding a floating base on a gantry (use physics: articulated)".into(),
            });
        }
        Ok(())
    }
    fn root_held(&self) -> bool {
        false
    }
}
