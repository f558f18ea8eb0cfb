//! [`RapierWorld`]: a fixed-base articulated rapier3d world loaded from a URDF.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::prelude::{
    ColliderBuilder, ColliderHandle, MultibodyDofCoupling, MultibodyJointHandle, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle,
};
use rapier3d_urdf::{UrdfLoaderOptions, UrdfMultibodyOptions, UrdfRobot};

use crate::description::{CollisionGeometry, CollisionShape, Description, PackagePaths};
use crate::physics::error::{Divergence, PhysicsError};
use crate::physics::friction::KineticFriction;
use crate::physics::model::{ArmModel, JointInfo, JointKind};
use crate::physics::obstacle::{Contact, ObstacleId, ObstacleShape};
use crate::physics::WorldConfig;

/// Solver iterations (substeps) per step for a floating base.
const FLOATING_SOLVER_ITERATIONS: usize = 2;

/// How one actuated URDF joint maps onto the rapier multibody.
#[derive(Debug, Clone, Copy)]
struct JointBinding {
    handle: MultibodyJointHandle,
    parent_body: RigidBodyHandle,
    child_body: RigidBodyHandle,
    /// Joint axis in the parent body's frame (rapier builds the joint frame with X = axis).
    axis_in_parent: Vector,
    /// Index into the joint's spatial coordinates: 0 = LinX (prismatic), 3 = AngX (revolute).
    coord_axis: usize,
    kind: JointKind,
}

/// An articulated world: one URDF tree as a rapier3d multibody, gravity, static
/// obstacles, and motor torques applied at the joints.
///
/// - Time advances only through [`RapierWorld::step`], by exactly `config.step_s`; rapier is
///   built with `enhanced-determinism`, so the same inputs give the same trajectory.
/// - Joint vectors (positions, velocities, torques) have one entry per actuated joint in the
///   order of [`RapierWorld::joints`] (URDF document order); units are rad, rad/s, N·m for
///   revolute joints and m, m/s, N for prismatic joints.
/// - The URDF root link is fixed to the world, or free above it
///   ([`WorldConfig::floating_base_height_m`]). Self-collisions are disabled (the primitive
///   collision shapes of neighbouring links overlap); links do collide with obstacles.
/// - Joint limits are rapier limit constraints, plus a projection after each step that puts a
///   joint that sank into its stop back on the limit (see `enforce_hard_stops`): observed
///   positions never lie outside the URDF limits. Effort and velocity limits are
///   *not* enforced here: the caller's motor model clamps its torque to
///   [`JointInfo::effort_limit`]. `<dynamics>` damping and friction and `<mimic>` couplings
///   from the URDF are applied, and so is each joint's armature (reflected rotor inertia, set
///   with [`RapierWorld::set_armature`]: URDF has no element for it). A joint's friction can be
///   split into its breakaway and kinetic values ([`RapierWorld::set_kinetic_friction`]);
///   joints never given a split keep the URDF value at every speed.
pub struct RapierWorld {
    model: ArmModel,
    config: WorldConfig,
    physics: PhysicsWorld,
    bindings: Vec<JointBinding>,
    /// Every rigid body of the arm with its URDF link name, for contact reports.
    link_bodies: Vec<(RigidBodyHandle, String)>,
    external_torques: Vec<f64>,
    /// Per joint: the sliding friction and stick band, for joints that have one (see
    /// [`RapierWorld::set_kinetic_friction`]); `None` keeps the URDF friction at every speed.
    kinetic_friction: Vec<Option<KineticFriction>>,
    /// Per joint: consecutive steps its speed has stayed inside its stick band (saturating;
    /// a joint placed or built at rest starts stuck).
    still_steps: Vec<u32>,
    obstacles: BTreeMap<ObstacleId, (RigidBodyHandle, ColliderHandle)>,
    next_obstacle: u64,
    steps: u64,
    warned_torque_len: bool,
    /// The first joint whose position or velocity stopped being finite, and the time it
    /// happened: kept once set (see [`RapierWorld::check_finite`]).
    diverged: Divergence,
}

impl std::fmt::Debug for RapierWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RapierWorld")
            .field("robot", &self.model.name())
            .field("joints", &self.model.joints().len())
            .field("obstacles", &self.obstacles.len())
            .field("time_s", &self.time_s())
            .finish()
    }
}

/// A collider per collision mesh of `geometry` (its hull's points), on the body of its link
/// or, for a link rapier3d-urdf merged into its parent over a fixed joint, on that body where
/// the link sits. Massless: the link's mass is its `<inertial>`'s.
fn add_mesh_hulls(
    physics: &mut PhysicsWorld,
    model: &ArmModel,
    bodies: &[(usize, RigidBodyHandle)],
    geometry: &CollisionGeometry,
) -> Result<(), PhysicsError> {
    let hulls: Vec<_> = geometry
        .shapes
        .iter()
        .filter_map(|s| match &s.shape {
            CollisionShape::Hull { points_m, .. } => Some((s, points_m)),
            _ => None,
        })
        .collect();
    if hulls.is_empty() {
        return Ok(());
    }
    let rest = model.link_poses(&vec![0.0; model.joints().len()])?;
    for (shape, points_m) in hulls {
        // The link itself, or the nearest ancestor that has a body (fixed joints between).
        let mut link = shape.link;
        let body = loop {
            if let Some((_, body)) = bodies.iter().find(|(l, _)| *l == link) {
                break Some(*body);
            }
            match model.parent_link(link) {
                Some(parent) => link = parent,
                None => break None,
            }
        };
        let Some(body) = body else { continue };
        let in_body = rest[link].inverse() * rest[shape.link] * shape.origin;
        let points: Vec<Vector> = points_m
            .iter()
            .map(|p| {
                let p = in_body * p;
                Vector::new(p.x as Real, p.y as Real, p.z as Real)
            })
            .collect();
        // Fewer than four points off a plane make no convex body for rapier: a plate's
        // collision mesh then collides as nothing here (the articulated world still has it).
        let Some(collider) = ColliderBuilder::convex_hull(&points) else {
            continue;
        };
        physics
            .colliders
            .insert_with_parent(collider.density(0.0), body, &mut physics.bodies);
    }
    Ok(())
}

fn vec3(v: [f64; 3]) -> Vector {
    Vector::new(v[0] as Real, v[1] as Real, v[2] as Real)
}

/// `value` if it stays finite in the physics' own precision: rapier computes in `Real`
/// (`f32`), where anything beyond ±3.4e38 (a finite 1e308 N·m in `f64`) is infinite and
/// turns the whole multibody into NaN within a step.
fn finite_in_physics(value: f64) -> Option<f64> {
    (value as Real).is_finite().then_some(value)
}

impl RapierWorld {
    /// Loads a URDF file (at most [`crate::physics::MAX_URDF_BYTES`]); its collision meshes are found
    /// from its folder and `ROS_PACKAGE_PATH` / `AMENT_PREFIX_PATH`, and collide with
    /// obstacles as their convex hulls.
    pub fn from_urdf_file(path: &Path, config: WorldConfig) -> Result<Self, PhysicsError> {
        let text = crate::physics::model::read_urdf(path)?;
        let paths = PackagePaths::for_urdf(path, Vec::new());
        Self::from_text(text, paths, config)
    }

    /// Loads URDF text (collision meshes only by absolute paths: text has no folder). See
    /// [`RapierWorld`] for what is simulated.
    pub fn from_urdf_str(xml: &str, config: WorldConfig) -> Result<Self, PhysicsError> {
        Self::from_text(xml.to_owned(), PackagePaths::default(), config)
    }

    fn from_text(
        text: String,
        paths: PackagePaths,
        config: WorldConfig,
    ) -> Result<Self, PhysicsError> {
        let (description, geometry) = Description::load_for_physics(text, paths)?;
        Self::from_description(&description, &geometry, config)
    }

    /// The world of a checked URDF with its collision geometry: rapier3d-urdf's bodies,
    /// joints and primitive colliders, plus a convex-hull collider per collision mesh.
    pub fn from_description(
        description: &Description,
        geometry: &CollisionGeometry,
        config: WorldConfig,
    ) -> Result<Self, PhysicsError> {
        if !(config.step_s.is_finite() && config.step_s > 0.0) {
            return Err(PhysicsError::InvalidConfig {
                reason: format!("step_s must be positive and finite, got {}", config.step_s),
            });
        }
        if config.gravity_m_s2.iter().any(|g| !g.is_finite()) {
            return Err(PhysicsError::InvalidConfig {
                reason: format!("gravity must be finite, got {:?}", config.gravity_m_s2),
            });
        }
        let robot = description.robot();
        let model = ArmModel::from_robot(robot)?;

        let mut physics = PhysicsWorld::new();
        physics.gravity = vec3(config.gravity_m_s2);
        physics.integration_parameters.dt = config.step_s as Real;
        // rapier substeps once per solver iteration and rebuilds the multibody mass matrix in
        // every substep: the default 4 iterations cost ~130 µs per Piper step, 1 costs ~42 µs.
        // At a 1 ms step one substep is enough: the holding-torque, limit and contact tests
        // pass unchanged (joint limits are projected exactly after the step anyway).
        physics.integration_parameters.num_solver_iterations = 1;
        if config.floating_base_height_m.is_some() {
            // A robot on the ground rests on contacts alone, and one iteration leaves them
            // jittering: the unpowered humanoid still moved at 1.6 rad/s after 5 s on the
            // ground. Two settle it at half the cost of four (robot_speed bench).
            physics.integration_parameters.num_solver_iterations = FLOATING_SOLVER_ITERATIONS;
        }

        if config
            .floating_base_height_m
            .is_some_and(|h| !(h.is_finite() && (h as Real).is_finite()))
        {
            return Err(PhysicsError::InvalidConfig {
                reason: format!(
                    "the floating base's start height must be finite, got {:?}",
                    config.floating_base_height_m
                ),
            });
        }
        let options = UrdfLoaderOptions {
            make_roots_fixed: config.floating_base_height_m.is_none(),
            shift: Pose::from_translation(Vector::new(
                0.0,
                0.0,
                config.floating_base_height_m.unwrap_or(0.0) as Real,
            )),
            // A held arm is at rest: it must not fall asleep and ignore the next torque.
            rigid_body_blueprint: RigidBodyBuilder::dynamic().can_sleep(false),
            ..UrdfLoaderOptions::default()
        };
        let urdf_robot = UrdfRobot::from_robot(robot, options, Path::new("."));
        let body_links: Vec<usize> = urdf_robot.links.iter().map(|l| l.urdf_link_index).collect();
        let link_names: Vec<String> = urdf_robot
            .links
            .iter()
            .map(|l| robot.links[l.urdf_link_index].name.clone())
            .collect();
        let joint_sources: Vec<(usize, Vec<usize>)> = urdf_robot
            .joints
            .iter()
            .map(|j| (j.urdf_joint_index, j.merged_urdf_joint_indices.clone()))
            .collect();
        let handles = urdf_robot.insert_using_multibody_joints(
            &mut physics.bodies,
            &mut physics.colliders,
            &mut physics.multibody_joints,
            UrdfMultibodyOptions::DISABLE_SELF_CONTACTS,
        );
        let link_bodies = handles
            .links
            .iter()
            .zip(link_names)
            .map(|(l, name)| (l.body, name))
            .collect();
        let bodies: Vec<(usize, RigidBodyHandle)> = body_links
            .iter()
            .zip(&handles.links)
            .map(|(&urdf, l)| (urdf, l.body))
            .collect();
        add_mesh_hulls(&mut physics, &model, &bodies, geometry)?;

        let mut bindings = Vec::with_capacity(model.joints().len());
        for (info, &u) in model.joints().iter().zip(model.urdf_joint_indices()) {
            let not_found = || PhysicsError::NotInMultibody {
                joint: info.name.clone(),
            };
            let k = joint_sources
                .iter()
                .position(|(src, _)| *src == u)
                .or_else(|| joint_sources.iter().position(|(_, m)| m.contains(&u)))
                .ok_or_else(not_found)?;
            let h = &handles.joints[k];
            let handle = h.joint.ok_or_else(not_found)?;
            let (mb, link_id) = physics.multibody_joints.get(handle).ok_or_else(not_found)?;
            let link = mb.link(link_id).ok_or_else(not_found)?;
            let axis_in_parent = link.joint.data.local_frame1.rotation * Vector::X;
            bindings.push(JointBinding {
                handle,
                parent_body: h.link1,
                child_body: h.link2,
                axis_in_parent,
                coord_axis: match info.kind {
                    JointKind::Prismatic => 0,
                    JointKind::Revolute => 3,
                },
                kind: info.kind,
            });
        }

        let mut world = Self {
            external_torques: vec![0.0; model.joints().len()],
            kinetic_friction: vec![None; model.joints().len()],
            still_steps: vec![u32::MAX; model.joints().len()],
            model,
            config,
            physics,
            bindings,
            link_bodies,
            obstacles: BTreeMap::new(),
            next_obstacle: 0,
            steps: 0,
            warned_torque_len: false,
            diverged: Divergence::default(),
        };
        world.apply_joint_dynamics();
        Ok(world)
    }

    /// Replaces rapier's default joint damping by the URDF `<dynamics>` values and turns
    /// `<mimic>` into multibody couplings.
    fn apply_joint_dynamics(&mut self) {
        let mb_joints = &mut self.physics.multibody_joints;
        for (info, b) in self.model.joints().iter().zip(&self.bindings) {
            if let Some((mb, link_id)) = mb_joints.get_mut(b.handle) {
                let Some(dof) = mb.link(link_id).map(|l| l.assembly_id()) else {
                    continue;
                };
                // rapier adds 0.1 N·m·s/rad on every angular DoF by default; the URDF decides.
                mb.damping_mut()[dof] = info.damping as Real;
                mb.frictions_mut()[dof] = info.friction as Real;
                mb.armature_mut()[dof] = info.armature as Real;
            }
        }
        for (info, b) in self.model.joints().iter().zip(&self.bindings) {
            let Some(m) = &info.mimic else { continue };
            let leader = self.bindings[m.leader_index];
            let Some((leader_mb, leader_link)) = mb_joints.get(leader.handle) else {
                continue;
            };
            let leader_root = leader_mb.root().rigid_body_handle();
            let Some((mb, follower_link)) = mb_joints.get_mut(b.handle) else {
                continue;
            };
            // A coupling links DoFs of one multibody; a fixed-base tree is always one.
            if mb.root().rigid_body_handle() != leader_root {
                tracing::warn!(joint = %info.name, leader = %m.leader, "mimic across multibodies ignored");
                continue;
            }
            mb.add_dof_coupling(MultibodyDofCoupling {
                link1: leader_link,
                dof1: 0,
                axis1: leader.coord_axis,
                link2: follower_link,
                dof2: 0,
                axis2: b.coord_axis,
                coeff: m.multiplier as Real,
                offset: m.offset as Real,
            });
        }
    }

    /// Sets the reflected rotor inertia (armature, kg·m² for a revolute joint, kg for a
    /// prismatic one) of actuated joint `joint`: gear ratio² × rotor inertia of its drive.
    ///
    /// URDF has no element for it. rapier adds it to the joint's diagonal entry of the
    /// multibody mass matrix (MuJoCo's `armature`), and so does [`ArmModel::mass_matrix`]: the
    /// rotor resists the joint's own acceleration only, which is what a geared motor's rotor
    /// does when its gear ratio is large. Negative or non-finite values count as 0; an unknown
    /// index is ignored.
    pub fn set_armature(&mut self, joint: usize, armature: f64) {
        self.model.set_armature(joint, armature);
        let (Some(info), Some(b)) = (self.model.joints().get(joint), self.bindings.get(joint))
        else {
            return;
        };
        if let Some((mb, link_id)) = self.physics.multibody_joints.get_mut(b.handle) {
            if let Some(dof) = mb.link(link_id).map(|l| l.assembly_id()) {
                mb.armature_mut()[dof] = info.armature as Real;
            }
        }
    }

    /// Splits actuated joint `joint`'s dry friction: its URDF `<dynamics friction>` becomes
    /// the breakaway (static) value it sees while its speed stays within
    /// `kinetic.stick_speed`, and `kinetic.kinetic` the value it sees while sliding faster
    /// (see [`KineticFriction`]). `None` restores the URDF value at every speed. Joints never
    /// given one keep their URDF friction; an unknown index is ignored.
    pub fn set_kinetic_friction(&mut self, joint: usize, kinetic: Option<KineticFriction>) {
        let Some(info) = self.model.joints().get(joint) else {
            return;
        };
        let breakaway = info.friction;
        if let Some(slot) = self.kinetic_friction.get_mut(joint) {
            *slot = kinetic.map(|k| KineticFriction::new(breakaway, k.kinetic, k.stick_speed));
        }
        self.apply_friction_regime(joint);
    }

    /// The static/kinetic split of actuated joint `joint`, if it has one.
    pub fn kinetic_friction(&self, joint: usize) -> Option<KineticFriction> {
        self.kinetic_friction.get(joint).copied().flatten()
    }

    /// The dry friction actuated joint `joint` sees in the next step (N·m or N): its
    /// breakaway value while stuck, its kinetic value while sliding. `None` for an unknown
    /// index.
    pub fn friction_in_effect(&self, joint: usize) -> Option<f64> {
        let b = self.bindings.get(joint)?;
        let (mb, link_id) = self.physics.multibody_joints.get(b.handle)?;
        let dof = mb.link(link_id)?.assembly_id();
        mb.frictions().get(dof).map(|f| f64::from(*f))
    }

    /// Sets the friction constraint of `joint` for its current stick count.
    fn apply_friction_regime(&mut self, joint: usize) {
        let (Some(info), Some(b)) = (self.model.joints().get(joint), self.bindings.get(joint))
        else {
            return;
        };
        let still = self.still_steps.get(joint).copied().unwrap_or(u32::MAX);
        let value = match self.kinetic_friction.get(joint).copied().flatten() {
            Some(k) => k.in_effect(info.friction, still),
            None => info.friction,
        };
        if let Some((mb, link_id)) = self.physics.multibody_joints.get_mut(b.handle) {
            if let Some(dof) = mb.link(link_id).map(|l| l.assembly_id()) {
                mb.frictions_mut()[dof] = value as Real;
            }
        }
    }

    /// Chooses static or kinetic friction for every joint with a split, from its speed at
    /// the start of the step (the speed rapier's friction constraint acts on).
    fn update_friction_regimes(&mut self) {
        if self.kinetic_friction.iter().all(Option::is_none) {
            return;
        }
        let velocities = self.joint_velocities();
        for (joint, velocity) in velocities.into_iter().enumerate() {
            let Some(k) = self.kinetic_friction.get(joint).copied().flatten() else {
                continue;
            };
            self.still_steps[joint] = if k.within_band(velocity) {
                self.still_steps[joint].saturating_add(1)
            } else {
                0
            };
            self.apply_friction_regime(joint);
        }
    }

    /// The URDF model this world was built from (limits, inertials, link kinematics).
    pub fn model(&self) -> &ArmModel {
        &self.model
    }

    /// The configuration the world was built with.
    pub fn config(&self) -> WorldConfig {
        self.config
    }

    /// The actuated joints in URDF document order: name, kind, limits, effort and velocity
    /// limits, damping, friction, armature, mimic.
    pub fn joints(&self) -> &[JointInfo] {
        self.model.joints()
    }

    /// Index of the actuated joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.model.joint_index(name)
    }

    fn check_vector(&self, values: &[f64]) -> Result<(), PhysicsError> {
        let joints = self.model.joints();
        if values.len() != joints.len() {
            return Err(PhysicsError::LengthMismatch {
                expected: joints.len(),
                actual: values.len(),
            });
        }
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(PhysicsError::NonFinite {
                joint: joints[i].name.clone(),
                value: *v,
            });
        }
        Ok(())
    }

    /// Teleports the arm to joint positions `q` (rad or m) with zero velocity.
    ///
    /// Every value must lie within its joint's limits. Mimic followers ignore their entry and
    /// are placed from their leader, so the coupling holds.
    pub fn set_joint_positions(&mut self, q: &[f64]) -> Result<(), PhysicsError> {
        self.check_vector(q)?;
        let joints = self.model.joints();
        let mut target = q.to_vec();
        for (i, j) in joints.iter().enumerate() {
            if let Some(m) = &j.mimic {
                target[i] = m.multiplier * q[m.leader_index] + m.offset;
            }
            if !j.within_limits(target[i]) {
                return Err(PhysicsError::OutOfLimit {
                    joint: j.name.clone(),
                    value: target[i],
                    lower: j.lower,
                    upper: j.upper,
                });
            }
        }
        let mb_joints = &mut self.physics.multibody_joints;
        for (b, &value) in self.bindings.iter().zip(&target) {
            if let Some((mb, link_id)) = mb_joints.get_mut(b.handle) {
                let Some(link) = mb.link(link_id) else {
                    continue;
                };
                let dof = link.assembly_id();
                let current = link.joint.coords()[b.coord_axis];
                let mut displacement = vec![0.0; mb.ndofs()];
                displacement[dof] = value as Real - current;
                mb.apply_displacements(&displacement);
            }
        }
        // A free root's pose lives in its rigid body (placed by the loader's shift, or where
        // the robot has moved to); without reading it, forward kinematics would put the root
        // back at the world origin. A fixed root is where it always was either way.
        let read_root_pose = self.config.floating_base_height_m.is_some();
        for b in &self.bindings {
            if let Some((mb, _)) = mb_joints.get_mut(b.handle) {
                mb.generalized_velocity_mut().fill(0.0);
                mb.forward_kinematics(&self.physics.bodies, read_root_pose);
                mb.update_rigid_bodies(&mut self.physics.bodies, true);
            }
        }
        for (body, _) in &self.link_bodies {
            if let Some(rb) = self.physics.bodies.get_mut(*body) {
                rb.set_linvel(Vector::ZERO, true);
                rb.set_angvel(Vector::ZERO, true);
            }
        }
        // Placed at rest: every joint starts stuck, as a real one would be.
        self.still_steps.fill(u32::MAX);
        for joint in 0..self.kinetic_friction.len() {
            self.apply_friction_regime(joint);
        }
        Ok(())
    }

    /// Advances the world by one fixed step of `config.step_s` with the motor torques
    /// (N·m, revolute) / forces (N, prismatic) `joint_torques` applied at the joints, plus the
    /// persistent external torques of [`RapierWorld::set_external_joint_torques`].
    ///
    /// Each joint torque is applied as an equal and opposite pair on the joint's two links (a
    /// pure torque about the joint axis; for a prismatic joint, opposite forces on one line
    /// of action), so it contributes exactly that generalized force to its own joint and
    /// nothing to the others. The torque is not clamped to the effort limit. Missing
    /// entries count as 0, extra entries are ignored, non-finite entries (in the physics'
    /// `f32` precision) count as 0.
    ///
    /// After the step every joint position and velocity is checked: the first one that is not
    /// finite is remembered and reported by [`RapierWorld::check_finite`] from then on (a
    /// diverged world does not recover; its owner must treat it as an error, not read zeros).
    pub fn step(&mut self, joint_torques: &[f64]) {
        if joint_torques.len() != self.bindings.len() && !self.warned_torque_len {
            // Once per world: a caller at 1 kHz would otherwise flood the log.
            self.warned_torque_len = true;
            tracing::warn!(
                expected = self.bindings.len(),
                actual = joint_torques.len(),
                "joint torque vector has the wrong length; missing entries count as 0"
            );
        }
        let bodies = &mut self.physics.bodies;
        for (body, _) in &self.link_bodies {
            if let Some(rb) = bodies.get_mut(*body) {
                rb.reset_forces(false);
                rb.reset_torques(false);
            }
        }
        for (i, b) in self.bindings.iter().enumerate() {
            let motor = joint_torques.get(i).copied().and_then(finite_in_physics);
            let total = motor.unwrap_or(0.0) + self.external_torques[i];
            if total == 0.0 {
                continue;
            }
            let Some(parent) = bodies.get(b.parent_body) else {
                continue;
            };
            let axis_w = parent.position().rotation * b.axis_in_parent;
            let amount = axis_w * total as Real;
            match b.kind {
                JointKind::Revolute => {
                    if let Some(child) = bodies.get_mut(b.child_body) {
                        child.add_torque(amount, true);
                    }
                    if let Some(parent) = bodies.get_mut(b.parent_body) {
                        parent.add_torque(-amount, true);
                    }
                }
                JointKind::Prismatic => {
                    let Some(child) = bodies.get_mut(b.child_body) else {
                        continue;
                    };
                    child.add_force(amount, true);
                    // Reaction on the parent along the same line of action (through the
                    // child's COM), so the pair carries no net moment.
                    let point = child.center_of_mass();
                    if let Some(parent) = bodies.get_mut(b.parent_body) {
                        parent.add_force_at_point(-amount, point, true);
                    }
                }
            }
        }
        self.update_friction_regimes();
        self.physics.step();
        self.enforce_hard_stops();
        self.steps += 1;
        if !self.diverged.happened() {
            self.detect_divergence();
        }
    }

    /// Remember the first joint whose position or velocity is no longer finite (logged once:
    /// at 1 kHz a message per step would flood the log).
    fn detect_divergence(&mut self) {
        let positions = self.joint_positions();
        let velocities = self.joint_velocities();
        let bad = positions
            .iter()
            .zip(&velocities)
            .position(|(q, v)| !(q.is_finite() && v.is_finite()));
        if let Some(i) = bad {
            let joint = self.model.joints()[i].name.clone();
            let time_s = self.time_s();
            tracing::error!(
                %joint,
                time_s,
                position = positions[i],
                velocity = velocities[i],
                "the physics diverged: a joint state is no longer finite"
            );
            self.diverged.record(joint, time_s);
        }
    }

    /// `Ok` while every joint position and velocity has stayed finite; once one has not, the
    /// [`PhysicsError::Diverged`] naming the first such joint and when it happened, for good.
    /// A diverged world reads NaN, which a wire codec would send as zeros (an arm "at rest at
    /// 0°"): callers must report this instead of its state.
    pub fn check_finite(&self) -> Result<(), PhysicsError> {
        self.diverged.check()
    }

    /// rapier's multibody limit constraint only engages once a joint is already past its limit,
    /// so a joint pushed into its stop sinks in by about `a·dt²` every step (≈ 3 mrad on the
    /// Piper wrist at 8 N·m). A mechanical stop does not give way: put such a joint back on
    /// its limit and drop the velocity component that points out of the range (an inelastic
    /// stop, which is also what rapier's constraint does to the approach velocity).
    fn enforce_hard_stops(&mut self) {
        let mb_joints = &mut self.physics.multibody_joints;
        let mut touched = Vec::new();
        for (info, b) in self.model.joints().iter().zip(&self.bindings) {
            let Some((mb, link_id)) = mb_joints.get_mut(b.handle) else {
                continue;
            };
            let Some(link) = mb.link(link_id) else {
                continue;
            };
            let dof = link.assembly_id();
            let q = f64::from(link.joint.coords()[b.coord_axis]);
            let (limit, outward) = if q < info.lower {
                (info.lower, -1.0)
            } else if q > info.upper {
                (info.upper, 1.0)
            } else {
                continue;
            };
            let mut displacement = vec![0.0; mb.ndofs()];
            displacement[dof] = (limit - q) as Real;
            mb.apply_displacements(&displacement);
            let mut velocities = mb.generalized_velocity_mut();
            if f64::from(velocities[dof]) * outward > 0.0 {
                velocities[dof] = 0.0;
            }
            touched.push(b.handle);
        }
        // As in `set_joint_positions`: a free root's pose is its rigid body's.
        let read_root_pose = self.config.floating_base_height_m.is_some();
        for handle in touched {
            if let Some((mb, _)) = mb_joints.get_mut(handle) {
                mb.forward_kinematics(&self.physics.bodies, read_root_pose);
                mb.update_rigid_bodies(&mut self.physics.bodies, false);
            }
        }
    }

    /// Joint positions, rad or m, in [`RapierWorld::joints`] order.
    pub fn joint_positions(&self) -> Vec<f64> {
        self.bindings
            .iter()
            .map(|b| {
                self.physics
                    .multibody_joints
                    .get(b.handle)
                    .and_then(|(mb, l)| mb.link(l))
                    .map_or(0.0, |link| f64::from(link.joint.coords()[b.coord_axis]))
            })
            .collect()
    }

    /// Joint velocities, rad/s or m/s, in [`RapierWorld::joints`] order.
    pub fn joint_velocities(&self) -> Vec<f64> {
        self.bindings
            .iter()
            .map(|b| {
                self.physics
                    .multibody_joints
                    .get(b.handle)
                    .and_then(|(mb, l)| mb.link(l).map(|link| (mb, link)))
                    .and_then(|(mb, link)| mb.joint_velocity(link).get(0).copied())
                    .map_or(0.0, f64::from)
            })
            .collect()
    }

    /// Sets disturbance torques (N·m) / forces (N) added at every joint on every following
    /// step until changed (e.g. a collision fault). Missing entries count as 0, extra entries
    /// are ignored, non-finite entries (in the physics' `f32` precision) count as 0.
    pub fn set_external_joint_torques(&mut self, tau: &[f64]) {
        for (i, slot) in self.external_torques.iter_mut().enumerate() {
            *slot = tau
                .get(i)
                .copied()
                .and_then(finite_in_physics)
                .unwrap_or(0.0);
        }
    }

    /// The external disturbance torques currently applied, one per joint.
    pub fn external_joint_torques(&self) -> &[f64] {
        &self.external_torques
    }

    /// Joint torques / forces that hold the arm still at `q` against this world's gravity,
    /// from the URDF inertials by our own code (see [`ArmModel::gravity_torques`]).
    pub fn gravity_torques(&self, q: &[f64]) -> Result<Vec<f64>, PhysicsError> {
        self.model.gravity_torques(q, self.config.gravity_m_s2)
    }

    /// Adds a static obstacle centred at `position_m` (world frame, m).
    pub fn add_obstacle(&mut self, shape: ObstacleShape, position_m: [f64; 3]) -> ObstacleId {
        let collider = match shape {
            ObstacleShape::Box { half_extents_m: h } => {
                ColliderBuilder::cuboid(h[0] as Real, h[1] as Real, h[2] as Real)
            }
            ObstacleShape::Sphere { radius_m } => ColliderBuilder::ball(radius_m as Real),
            // rapier cylinders stand along Y; turn them to stand along Z.
            ObstacleShape::Cylinder {
                radius_m,
                half_height_m,
            } => ColliderBuilder::cylinder(half_height_m as Real, radius_m as Real)
                .rotation(Vector::X * std::f32::consts::FRAC_PI_2),
        };
        let body = RigidBodyBuilder::fixed().translation(vec3(position_m));
        let (body, collider) = self.physics.insert(body, collider);
        let id = ObstacleId(self.next_obstacle);
        self.next_obstacle += 1;
        self.obstacles.insert(id, (body, collider));
        id
    }

    /// Removes an obstacle; unknown ids are ignored.
    pub fn remove_obstacle(&mut self, id: ObstacleId) {
        if let Some((body, _)) = self.obstacles.remove(&id) {
            let p = &mut self.physics;
            p.bodies.remove(
                body,
                &mut p.islands,
                &mut p.colliders,
                &mut p.impulse_joints,
                &mut p.multibody_joints,
                &mut p.soft_bodies,
                true,
            );
        }
    }

    /// Arm links touching obstacles after the last step, sorted by link name then obstacle.
    /// A link with several collision shapes on one obstacle gives one entry (deepest
    /// penetration, summed force).
    pub fn contacts(&self) -> Vec<Contact> {
        let mut merged: BTreeMap<(String, ObstacleId), (f64, f64)> = BTreeMap::new();
        for (&id, &(_, obstacle)) in &self.obstacles {
            for pair in self.physics.narrow_phase.contact_pairs_with(obstacle) {
                if !pair.has_any_active_contact() {
                    continue;
                }
                let other = if pair.collider1 == obstacle {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let Some(body) = self.physics.colliders.get(other).and_then(|c| c.parent()) else {
                    continue;
                };
                let Some((_, link)) = self.link_bodies.iter().find(|(b, _)| *b == body) else {
                    continue;
                };
                let deepest_dist_m = pair
                    .find_deepest_contact()
                    .map_or(f64::INFINITY, |(_, c)| f64::from(c.dist));
                let force = f64::from(pair.total_impulse_magnitude()) / self.config.step_s;
                // rapier also keeps speculative contacts up to 2 cm apart: report a pair only
                // when the shapes touch or the solver had to push.
                if deepest_dist_m > 0.0 && force == 0.0 {
                    continue;
                }
                let depth = (-deepest_dist_m).max(0.0);
                let entry = merged.entry((link.clone(), id)).or_insert((0.0, 0.0));
                entry.0 = entry.0.max(depth);
                entry.1 += force;
            }
        }
        merged
            .into_iter()
            .map(
                |((link, obstacle), (penetration_m, normal_force_n))| Contact {
                    link,
                    obstacle,
                    penetration_m,
                    normal_force_n,
                },
            )
            .collect()
    }

    /// Pose of a link's frame in the world as rapier currently has it (`None` for an unknown
    /// link or one that rapier merged away).
    pub fn link_pose(&self, link: &str) -> Option<Isometry3<f64>> {
        let (body, _) = self.link_bodies.iter().find(|(_, n)| n == link)?;
        let pose: &Pose = self.physics.bodies.get(*body)?.position();
        let t = pose.translation;
        let r = pose.rotation;
        Some(Isometry3::from_parts(
            Translation3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z)),
            UnitQuaternion::from_quaternion(Quaternion::new(
                f64::from(r.w),
                f64::from(r.x),
                f64::from(r.y),
                f64::from(r.z),
            )),
        ))
    }

    /// Simulated time: number of steps × `config.step_s`, s.
    pub fn time_s(&self) -> f64 {
        self.steps as f64 * self.config.step_s
    }

    /// Number of steps taken since the world was built.
    pub fn steps(&self) -> u64 {
        self.steps
    }
}
