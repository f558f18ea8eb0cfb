//! One physics world for a whole robot, its actuated joints bound to the actuators' plants.

use crate::description::{Description, DescriptionError};
use crate::physics::articulated::ArticulatedWorld;
use crate::physics::{PhysicsError, Solver, World, WorldConfig};

use super::config::{Base, Gantry, RobotConfig};
use super::joint_plant::{joint_pair, JointLink, JointPlant};

/// World steps between two refreshes of the joints' effective inertia: it changes with the
/// pose, slowly at the speeds a robot moves, and the mass matrix costs more than a step.
const INERTIA_REFRESH_STEPS: u64 = 10;

/// Joint speed under which a joint counts as still, rad/s (m/s).
const REST_SPEED_RAD_S: f64 = 1e-5;

/// Change of a joint's torque from one step to the next under which the torques count as the
/// same, N·m: a firmware holding a still joint computes the same torque step after step.
const REST_TORQUE_CHANGE_NM: f64 = 1e-9;

/// The robot's world and, per actuator, the link to its joint.
pub struct RobotWorld {
    world: Box<dyn World>,
    /// Per actuator (configuration order): the world's joint index and the link.
    joints: Vec<(usize, JointLink)>,
    /// Per world joint, the torque applied in the last step (N·m).
    applied_nm: Vec<f64>,
    /// Per world joint, the torque of the last step the world took (N·m).
    stepped_nm: Vec<f64>,
    /// 1 ms steps since power-on, the world's own and those it rested through.
    steps: u64,
    /// Every joint was still after the last two world steps, under the same torques, with the
    /// base fixed or held: the world is at rest and is not stepped (as a physics engine lets
    /// a body at rest sleep) until a torque changes or the stand lets go.
    resting: bool,
    /// Every joint was still after the last world step.
    was_still: bool,
    /// Whether the base is bolted down (a fixed base).
    fixed_base: bool,
    /// Length of one step (s).
    step_s: f64,
}

impl std::fmt::Debug for RobotWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotWorld")
            .field("world", &self.world)
            .field("actuators", &self.joints.len())
            .finish()
    }
}

/// Why a robot's world could not be built.
#[derive(Debug, thiserror::Error)]
pub enum RobotWorldError {
    /// The URDF did not load into the physics world.
    #[error(transparent)]
    Physics(#[from] PhysicsError),
    /// The URDF, or a mesh it names, is not one the physics can run.
    #[error("the URDF: {0}")]
    Description(#[from] DescriptionError),
    /// An actuator or start position names a joint the URDF does not have (or one that is
    /// fixed).
    #[error("joint `{joint}` is not a revolute, continuous or prismatic joint of the URDF (its movable joints: {known})")]
    UnknownJoint {
        /// The name given.
        joint: String,
        /// The URDF's movable joints, comma-separated.
        known: String,
    },
}

impl RobotWorld {
    /// Loads the robot's URDF with its base, sets the start positions and each actuator's
    /// rotor inertia, and returns the world with one [`JointPlant`] per actuator (in
    /// configuration order) for the actuators' firmware.
    pub fn new(config: &RobotConfig) -> Result<(Self, Vec<JointPlant>), RobotWorldError> {
        // The articulated-body solver by default rather than rapier's multibody: a humanoid's
        // 26 degrees of freedom cost rapier a dense mass matrix per substep (290-460 µs per
        // 1 ms step), the solver walks the tree (~33 µs; see `physics::articulated`).
        let world_config = WorldConfig {
            floating_base_height_m: match config.base {
                Base::Fixed => None,
                Base::Floating { start_height_m } => Some(start_height_m),
            },
            ..WorldConfig::default()
        };
        let description = Description::parse(config.urdf.clone(), config.urdf_paths.clone())?;
        let geometry = match &config.collision {
            Some(geometry) => std::sync::Arc::clone(geometry),
            None => std::sync::Arc::new(description.collision_geometry_decomposed(
                config.missing_meshes,
                &config.convex_decomposition,
            )?),
        };
        let mut world: Box<dyn World> = match (config.physics, &config.self_collision) {
            (Solver::Articulated, excluded) => {
                let mut world =
                    ArticulatedWorld::from_description(&description, &geometry, world_config)?;
                if let Some(excluded) = excluded {
                    world.enable_self_collision(&geometry, excluded)?;
                }
                Box::new(world)
            }
            (Solver::Rapier, None) => Solver::Rapier.load(&description, &geometry, world_config)?,
            (Solver::Rapier, Some(_)) => {
                return Err(PhysicsError::Unsupported {
                    what: "self-collision (the articulated solver's: physics: articulated)".into(),
                }
                .into())
            }
        };
        let index_of = |name: &str| {
            world
                .joint_index(name)
                .ok_or_else(|| RobotWorldError::UnknownJoint {
                    joint: name.to_owned(),
                    known: world
                        .joints()
                        .iter()
                        .map(|j| j.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                })
        };
        let mut q = vec![0.0; world.joints().len()];
        for (name, value) in &config.start_positions_rad {
            q[index_of(name)?] = *value;
        }
        let mut indices = Vec::with_capacity(config.actuators.len());
        for actuator in &config.actuators {
            let index = index_of(&actuator.joint)?;
            indices.push(index);
        }
        for (actuator, &index) in config.actuators.iter().zip(&indices) {
            world.set_armature(index, actuator.actuator.model().rotor_inertia_kg_m2);
        }
        world.set_joint_positions(&q)?;
        let floating = matches!(config.base, Base::Floating { .. });
        world.set_root_held(floating && config.gantry != Gantry::Off)?;
        let inertia = world.mass_matrix_diagonal();
        let mut joints = Vec::with_capacity(indices.len());
        let mut plants = Vec::with_capacity(indices.len());
        for (actuator, &index) in config.actuators.iter().zip(&indices) {
            let (link, plant) = joint_pair(
                actuator.direction,
                actuator.zero_offset_rad,
                q[index],
                inertia[index],
            );
            joints.push((index, link));
            plants.push(plant);
        }
        let applied_nm = vec![0.0; world.joints().len()];
        Ok((
            Self {
                world,
                joints,
                stepped_nm: applied_nm.clone(),
                applied_nm,
                steps: 0,
                resting: false,
                was_still: false,
                fixed_base: !floating,
                step_s: world_config.step_s,
            },
            plants,
        ))
    }

    /// One 1 ms world step with the torques the actuators applied since the last one; then
    /// every joint's state goes back to its actuator. An `Err` means the physics diverged.
    pub fn step(&mut self) -> Result<(), PhysicsError> {
        self.steps += 1;
        self.applied_nm.fill(0.0);
        for (index, link) in &self.joints {
            self.applied_nm[*index] = link.take_joint_torque_nm();
        }
        let same_torques = self
            .applied_nm
            .iter()
            .zip(&self.stepped_nm)
            .all(|(now, then)| (now - then).abs() <= REST_TORQUE_CHANGE_NM);
        if self.resting && same_torques {
            // At rest under the torques that keep it there: the joints' states stand.
            return Ok(());
        }
        self.world.step(&self.applied_nm);
        self.world.check_finite()?;
        self.stepped_nm.clone_from(&self.applied_nm);
        let q = self.world.joint_positions();
        let qd = self.world.joint_velocities();
        // Still twice in a row under the same torques: no joint is at the turn of a swing
        // (where it is still for an instant but accelerating), so the world is in balance.
        // A floating base left to its contacts is never taken as at rest.
        let still = qd.iter().all(|v| v.abs() < REST_SPEED_RAD_S);
        let anchored = self.fixed_base || self.world.root_held();
        self.resting = still && self.was_still && same_torques && anchored;
        self.was_still = still;
        let refresh = self.world.steps().is_multiple_of(INERTIA_REFRESH_STEPS);
        let inertia = if refresh {
            Some(self.world.mass_matrix_diagonal())
        } else {
            None
        };
        for (index, link) in &self.joints {
            let i = *index;
            link.sync_from_world(q[i], qd[i], inertia.as_ref().map(|m| m[i]));
        }
        Ok(())
    }

    /// Lets the stand go of the base (see [`Gantry`]); `false` when it held nothing.
    pub fn release_base(&mut self) -> bool {
        self.resting = false;
        self.was_still = false;
        let held = self.world.root_held();
        // Letting go is within every solver's reach (one that cannot hold never held).
        let _ = self.world.set_root_held(false);
        held
    }

    /// The physics world (positions, link poses for views and checks).
    pub fn world(&self) -> &dyn World {
        self.world.as_ref()
    }

    /// Emulated time since power-on (s): the steps taken and those rested through.
    pub fn time_s(&self) -> f64 {
        self.steps as f64 * self.step_s
    }

    /// The world's joint index of actuator `actuator` (configuration order).
    pub fn joint_index(&self, actuator: usize) -> Option<usize> {
        self.joints.get(actuator).map(|(i, _)| *i)
    }
}
