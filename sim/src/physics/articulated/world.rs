//! [`ArticulatedWorld`]: a URDF tree stepped by Featherstone's articulated-body algorithm.

use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};

use super::contact::GroundContacts;
use super::self_contact::SelfContacts;
use super::spatial::{
    angular, cross_force, cross_motion, linear, motion_transform, spatial, spatial_inertia,
};
use crate::description::{CollisionGeometry, Description, PackagePaths};
use crate::physics::error::Divergence;
use crate::physics::model::{TreeJoint, TreeJointKind};
use crate::physics::{ArmModel, JointInfo, PhysicsError, WorldConfig};

/// Stiffness of a joint's stop past its limit (N·m/rad, N/m): the stop is a spring treated
/// implicitly (stable however stiff). Not a projection back onto the limit: zeroing a joint's
/// speed without the reaction on the rest of a free robot would create momentum, and energy.
const STOP_STIFFNESS: f64 = 1.0e5;
/// Damping of a joint's stop (N·m·s/rad, N·s/m): an inelastic stop.
const STOP_DAMPING: f64 = 100.0;
/// Below this speed (rad/s, m/s) a joint's dry friction acts as a stiff damper (implicit),
/// which holds a joint still without the chatter of a switching sign.
const FRICTION_STICK_SPEED: f64 = 0.01;
/// Friction coefficient between every link and the ground (rapier's default for both).
const GROUND_FRICTION: f64 = 0.5;

/// Substeps per step: contacts are explicit springs and need short substeps (0.25 ms; at
/// 0.5 ms a light link's contact damping is near the edge of stability).
pub const SUBSTEPS: u32 = 4;

/// Per tree joint, what one pass of the algorithm keeps.
#[derive(Debug, Clone, Copy)]
struct JointPass {
    /// Motion transform parent → child.
    x: Matrix6<f64>,
    /// Velocity-product acceleration.
    c: Vector6<f64>,
    /// `I^A · S`.
    u_vec: Vector6<f64>,
    /// `Sᵀ · I^A · S` plus everything treated implicitly on the joint.
    d: f64,
    /// Joint force left after the bias.
    u: f64,
}

impl Default for JointPass {
    fn default() -> Self {
        Self {
            x: Matrix6::identity(),
            c: Vector6::zeros(),
            u_vec: Vector6::zeros(),
            d: 1.0,
            u: 0.0,
        }
    }
}

/// One URDF tree, fixed or free at its root, stepped in `O(links)` per substep with
/// Featherstone's articulated-body algorithm and ground contact from its collision primitives.
///
/// What it simulates, and how it differs from the rapier world ([`crate::physics::RapierWorld`]):
/// - joints: motor and external torques, each joint's armature (on the articulated
///   inertia), URDF damping and dry friction (both implicit), stops at the URDF limits
///   (a stiff implicit spring; observed positions are clamped to the limits); `<mimic>`
///   followers placed by their leaders after every substep; no obstacles but the ground;
/// - a free root: gravity on every link and the ground plane z = 0 touching the links'
///   collision shapes (meshes by their hulls' contact points) and primitives (boxes by their corners, cylinders by points on their rims,
///   spheres and capsule ends as spheres) through stiff springs, friction anchored where a
///   point lands so a standing robot does not creep; no self-collision.
///
/// Semi-implicit Euler on positions, velocities and the root's pose; deterministic.
pub struct ArticulatedWorld {
    model: ArmModel,
    config: WorldConfig,
    /// Spatial inertia of every link about its origin (link order).
    inertia: Vec<Matrix6<f64>>,
    contacts: GroundContacts,
    q: Vec<f64>,
    qd: Vec<f64>,
    /// The root link's pose in the world.
    root_pose: Isometry3<f64>,
    /// The root link's spatial velocity in its own coordinates (zero for a fixed root).
    root_velocity: Vector6<f64>,
    external_torques: Vec<f64>,
    /// A floating root held where it is (a robot on its stand): it moves as a fixed root.
    root_held: bool,
    /// Links touching links, when asked for ([`ArticulatedWorld::enable_self_collision`]).
    self_contacts: Option<SelfContacts>,
    /// Per `<mimic>` follower: (follower, leader, multiplier, offset), actuated indices.
    followers: Vec<(usize, usize, f64, f64)>,
    /// Per actuated joint, whether it follows another through `<mimic>`.
    is_follower: Vec<bool>,
    steps: u64,
    /// The first joint whose state stopped being finite, and when.
    diverged: Divergence,
}

impl std::fmt::Debug for ArticulatedWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ArticulatedWorld")
            .field("robot", &self.model.name())
            .field("joints", &self.q.len())
            .field("time_s", &self.time_s())
            .finish()
    }
}

/// The joint's motion subspace in the child's coordinates.
fn motion_subspace(joint: &TreeJoint) -> Option<Vector6<f64>> {
    match joint.kind {
        TreeJointKind::Fixed => None,
        TreeJointKind::Revolute => Some(spatial(joint.axis, Vector3::zeros())),
        TreeJointKind::Prismatic => Some(spatial(Vector3::zeros(), joint.axis)),
    }
}

/// The child link's pose in its parent's frame at joint position `q`.
fn child_in_parent(joint: &TreeJoint, q: f64) -> Isometry3<f64> {
    let motion = match joint.kind {
        TreeJointKind::Fixed => Isometry3::identity(),
        TreeJointKind::Revolute => Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_scaled_axis(joint.axis * q),
        ),
        TreeJointKind::Prismatic => Isometry3::from_parts(
            Translation3::from(joint.axis * q),
            UnitQuaternion::identity(),
        ),
    };
    joint.origin * motion
}

impl ArticulatedWorld {
    /// Loads URDF text whose collision shapes are primitives or meshes named by absolute
    /// paths (relative names have no folder to start from: use
    /// [`ArticulatedWorld::from_description`]). A floating base
    /// (`config.floating_base_height_m`) stands on the ground, the plane z = 0.
    pub fn from_urdf_str(xml: &str, config: WorldConfig) -> Result<Self, PhysicsError> {
        let (description, geometry) =
            Description::load_for_physics(xml.to_owned(), PackagePaths::default())?;
        Self::from_description(&description, &geometry, config)
    }

    /// The world of a checked URDF with its collision geometry (meshes read and hulled).
    pub fn from_description(
        description: &Description,
        geometry: &CollisionGeometry,
        config: WorldConfig,
    ) -> Result<Self, PhysicsError> {
        let model = ArmModel::from_robot(description.robot())?;
        let inertia = model.inertials().iter().map(spatial_inertia).collect();
        let n = model.joints().len();
        let root_pose =
            Isometry3::translation(0.0, 0.0, config.floating_base_height_m.unwrap_or(0.0));
        let followers: Vec<(usize, usize, f64, f64)> = model
            .joints()
            .iter()
            .enumerate()
            .filter_map(|(f, j)| {
                let m = j.mimic.as_ref()?;
                Some((f, m.leader_index, m.multiplier, m.offset))
            })
            .collect();
        let mut is_follower = vec![false; n];
        for &(f, ..) in &followers {
            is_follower[f] = true;
        }
        let world = Self {
            self_contacts: None,
            root_held: false,
            followers,
            is_follower,
            contacts: GroundContacts::new(geometry, GROUND_FRICTION),
            model,
            config,
            inertia,
            q: vec![0.0; n],
            qd: vec![0.0; n],
            root_pose,
            root_velocity: Vector6::zeros(),
            external_torques: vec![0.0; n],
            steps: 0,
            diverged: Divergence::default(),
        };
        // Every driven joint must move something: a zero effective inertia is a division by
        // zero at the first step (public URDFs have hands of massless links).
        let diagonal = world.mass_matrix_diagonal();
        for (a, joint) in world.model.joints().iter().enumerate() {
            if !world.is_follower[a] && diagonal[a] <= 1e-12 {
                return Err(PhysicsError::MasslessJoint {
                    joint: joint.name.clone(),
                });
            }
        }
        Ok(world)
    }

    /// The model (kinematics, inertials, limits).
    pub fn model(&self) -> &ArmModel {
        &self.model
    }

    /// The actuated joints, in URDF document order.
    pub fn joints(&self) -> &[JointInfo] {
        self.model.joints()
    }

    /// Index of the actuated joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.model.joint_index(name)
    }

    /// Sets joint `joint`'s armature (reflected rotor inertia, kg·m² or kg).
    pub fn set_armature(&mut self, joint: usize, armature: f64) {
        self.model.set_armature(joint, armature);
    }

    /// Places the joints at `q` at rest (clamped to their limits).
    pub fn set_joint_positions(&mut self, q: &[f64]) -> Result<(), PhysicsError> {
        if q.len() != self.q.len() {
            return Err(PhysicsError::LengthMismatch {
                expected: self.q.len(),
                actual: q.len(),
            });
        }
        for (i, (value, info)) in q.iter().zip(self.model.joints()).enumerate() {
            if !value.is_finite() {
                return Err(PhysicsError::NonFinite {
                    joint: info.name.clone(),
                    value: *value,
                });
            }
            self.q[i] = value.clamp(info.lower, info.upper);
        }
        self.qd.fill(0.0);
        self.follow_leaders();
        Ok(())
    }

    /// Makes the links of `geometry` (this world's collision geometry) touch each other:
    /// every pair of shapes on two links that no joint joins and that `excluded` (pairs of
    /// link names, either order) does not name; pairs that overlap in the pose of the first
    /// step are left out (neighbours' published meshes often do). Returns the pairs watched
    /// before that pruning; an unknown link name is an error naming it.
    pub fn enable_self_collision(
        &mut self,
        geometry: &CollisionGeometry,
        excluded: &[(String, String)],
    ) -> Result<usize, PhysicsError> {
        let model = &self.model;
        let mut pairs = Vec::with_capacity(excluded.len());
        for (a, b) in excluded {
            let index = |name: &str| {
                model
                    .link_index(name)
                    .ok_or_else(|| PhysicsError::UnknownLink {
                        joint: "self-collision exclusion".to_owned(),
                        link: name.to_owned(),
                    })
            };
            pairs.push((index(a)?, index(b)?));
        }
        let joined =
            |a: usize, b: usize| model.parent_link(a) == Some(b) || model.parent_link(b) == Some(a);
        let excluded = |a: usize, b: usize| pairs.contains(&(a, b)) || pairs.contains(&(b, a));
        let contacts = SelfContacts::new(geometry, joined, excluded);
        let count = contacts.pair_count();
        self.self_contacts = Some(contacts);
        Ok(count)
    }

    /// Holds a floating root where it is now (`true`: a stand takes its weight, it moves no
    /// more) or lets it go from rest (`false`). No effect on a fixed root.
    pub fn set_root_held(&mut self, held: bool) {
        if held != self.root_held {
            self.root_velocity = Vector6::zeros();
        }
        self.root_held = held;
    }

    /// Whether a stand holds the root (see [`ArticulatedWorld::set_root_held`]).
    pub fn root_held(&self) -> bool {
        self.root_held
    }

    /// Disturbance torques (N·m, N) added to every step's motor torques until changed.
    pub fn set_external_joint_torques(&mut self, tau: &[f64]) {
        for (slot, value) in self.external_torques.iter_mut().zip(tau) {
            *slot = if value.is_finite() { *value } else { 0.0 };
        }
    }

    /// One step of `config.step_s` with motor torques `joint_torques` (missing entries 0).
    pub fn step(&mut self, joint_torques: &[f64]) {
        let substeps = SUBSTEPS;
        let dt = self.config.step_s / f64::from(substeps);
        let tau: Vec<f64> = (0..self.q.len())
            .map(|i| {
                let motor = joint_torques.get(i).copied().filter(|t| t.is_finite());
                motor.unwrap_or(0.0) + self.external_torques[i]
            })
            .collect();
        for _ in 0..substeps {
            self.substep(&tau, dt);
        }
        self.steps += 1;
        if !self.diverged.happened() {
            self.detect_divergence();
        }
    }

    /// Every link's pose in the world at the current state (link order).
    pub fn link_poses(&self) -> Vec<Isometry3<f64>> {
        let mut poses = vec![Isometry3::identity(); self.inertia.len()];
        poses[self.model.root_link()] = self.root_pose;
        for joint in self.model.tree() {
            let q = joint.actuated.map_or(0.0, |a| self.q[a]);
            poses[joint.child] = poses[joint.parent] * child_in_parent(joint, q);
        }
        poses
    }

    /// The pose of link `link` in the world.
    pub fn link_pose(&self, link: &str) -> Option<Isometry3<f64>> {
        let index = self.model.link_index(link)?;
        Some(self.link_poses()[index])
    }

    /// Kinetic energy of every link together (J), for tests of the solver.
    #[cfg(test)]
    pub(super) fn kinetic_energy_j(&self) -> f64 {
        let links = self.inertia.len();
        let mut velocity = vec![Vector6::zeros(); links];
        velocity[self.model.root_link()] = self.root_velocity;
        for joint in self.model.tree() {
            let q = joint.actuated.map_or(0.0, |a| self.q[a]);
            let x = motion_transform(&child_in_parent(joint, q));
            let joint_velocity = match (motion_subspace(joint), joint.actuated) {
                (Some(s), Some(a)) => s * self.qd[a],
                _ => Vector6::zeros(),
            };
            velocity[joint.child] = x * velocity[joint.parent] + joint_velocity;
        }
        let links_energy: f64 = velocity
            .iter()
            .zip(&self.inertia)
            .map(|(v, i)| 0.5 * v.dot(&(i * v)))
            .sum();
        let rotors: f64 = self
            .model
            .joints()
            .iter()
            .zip(&self.qd)
            .map(|(j, qd)| 0.5 * j.armature * qd * qd)
            .sum();
        links_energy + rotors
    }

    /// Joint positions (rad, m), never outside the URDF limits: a joint pressed into its stop
    /// sinks into it by its load over the stop's stiffness (80 N·m: 0.8 mrad), which an
    /// encoder on the real joint would not see either.
    pub fn joint_positions(&self) -> Vec<f64> {
        self.q
            .iter()
            .zip(self.model.joints())
            .map(|(q, info)| q.clamp(info.lower, info.upper))
            .collect()
    }

    /// Joint velocities (rad/s, m/s).
    pub fn joint_velocities(&self) -> Vec<f64> {
        self.qd.clone()
    }

    /// Emulated time, s.
    pub fn time_s(&self) -> f64 {
        self.steps as f64 * self.config.step_s
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// `Ok` while every joint state has stayed finite; then the first joint that did not.
    pub fn check_finite(&self) -> Result<(), PhysicsError> {
        self.diverged.check()
    }

    fn detect_divergence(&mut self) {
        let root_ok = self.root_velocity.iter().all(|v| v.is_finite())
            && self
                .root_pose
                .translation
                .vector
                .iter()
                .all(|v| v.is_finite());
        let bad = self
            .q
            .iter()
            .zip(&self.qd)
            .position(|(q, v)| !(q.is_finite() && v.is_finite()));
        let joint = match (bad, root_ok) {
            (Some(i), _) => self.model.joints()[i].name.clone(),
            (None, false) => self.model.link_names()[self.model.root_link()].clone(),
            (None, true) => return,
        };
        tracing::error!(%joint, time_s = self.time_s(), "the physics diverged: a joint state is no longer finite");
        self.diverged.record(joint, self.time_s());
    }

    /// The joint force of everything treated on the joint itself, explicit part, and what
    /// it adds to the joint's inertia when treated implicitly over `dt`.
    fn joint_terms(&self, a: usize, tau: f64, dt: f64) -> (f64, f64) {
        let info = &self.model.joints()[a];
        let (q, qd) = (self.q[a], self.qd[a]);
        let mut force = tau - info.damping * qd;
        let mut implicit = info.armature + info.damping * dt;
        if info.friction > 0.0 {
            if qd.abs() < FRICTION_STICK_SPEED {
                let b = info.friction / FRICTION_STICK_SPEED;
                force -= b * qd;
                implicit += b * dt;
            } else {
                force -= info.friction * qd.signum();
            }
        }
        let ahead = q + qd * dt;
        let past = if ahead < info.lower {
            ahead - info.lower
        } else if ahead > info.upper {
            ahead - info.upper
        } else {
            0.0
        };
        if past != 0.0 {
            force -= STOP_STIFFNESS * past + STOP_DAMPING * qd;
            implicit += STOP_STIFFNESS * dt * dt + STOP_DAMPING * dt;
        }
        (force, implicit)
    }

    /// Puts every `<mimic>` follower where its leader says: `q = multiplier · q_leader +
    /// offset`, and its speed likewise. A follower is carried rigidly by its parent within a
    /// substep (its subtree's mass counts on the parent, its motor and stop do not act) and
    /// placed here after each one: exact in position, stable however light the follower.
    fn follow_leaders(&mut self) {
        for &(f, leader, multiplier, offset) in &self.followers {
            self.q[f] = multiplier * self.q[leader] + offset;
            self.qd[f] = multiplier * self.qd[leader];
        }
    }

    /// The diagonal of the joint-space mass matrix at the current positions with the base
    /// held (kg·m², kg), armature included: per joint, the inertia its motor drives when the
    /// others are held still. One pass of composite inertias from the leaves, `O(links)`.
    pub fn mass_matrix_diagonal(&self) -> Vec<f64> {
        let mut composite = self.inertia.clone();
        let tree = self.model.tree();
        let mut diagonal = vec![0.0; self.q.len()];
        for joint in tree.iter().rev() {
            let q = joint.actuated.map_or(0.0, |a| self.q[a]);
            let x = motion_transform(&child_in_parent(joint, q));
            let child = composite[joint.child];
            if let (Some(s), Some(a)) = (motion_subspace(joint), joint.actuated) {
                diagonal[a] = s.dot(&(child * s)) + self.model.joints()[a].armature;
            }
            composite[joint.parent] += x.transpose() * child * x;
        }
        diagonal
    }

    fn substep(&mut self, tau: &[f64], dt: f64) {
        let (qdd, root_acceleration) = self.accelerations(tau, dt);
        // Semi-implicit Euler: velocities, then positions with the new velocities.
        for ((q, qd), acceleration) in self.q.iter_mut().zip(&mut self.qd).zip(&qdd) {
            *qd += acceleration * dt;
            *q += *qd * dt;
        }
        self.follow_leaders();
        if self.config.floating_base_height_m.is_some() && !self.root_held {
            // The root's velocity is in its own coordinates; for spatial vectors their rate
            // there is the acceleration in them (v × v = 0).
            self.root_velocity += root_acceleration * dt;
            let v = self.root_velocity;
            let rotation = self.root_pose.rotation;
            self.root_pose.translation.vector += rotation * linear(&v) * dt;
            self.root_pose.rotation = rotation * UnitQuaternion::from_scaled_axis(angular(&v) * dt);
        }
    }

    /// Joint accelerations and the root's (its own coordinates) under joint forces `tau`,
    /// with the joint terms treated implicitly over `dt` (0: the plain dynamics, as tests
    /// compare them with the mass matrix).
    pub(super) fn accelerations(&mut self, tau: &[f64], dt: f64) -> (Vec<f64>, Vector6<f64>) {
        let tree = self.model.tree();
        let links = self.inertia.len();
        let root = self.model.root_link();
        let floating = self.config.floating_base_height_m.is_some();
        // Held on its stand, a floating root moves as a fixed one; the ground still pushes
        // on feet that reach it.
        let free = floating && !self.root_held;
        let gravity = Vector3::from(self.config.gravity_m_s2);

        // Pass 1, root to leaves: poses, velocities, bias forces.
        let mut poses = vec![Isometry3::identity(); links];
        let mut velocity = vec![Vector6::zeros(); links];
        let mut passes = vec![JointPass::default(); tree.len()];
        poses[root] = self.root_pose;
        velocity[root] = if free {
            self.root_velocity
        } else {
            Vector6::zeros()
        };
        for (k, joint) in tree.iter().enumerate() {
            let q = joint.actuated.map_or(0.0, |a| self.q[a]);
            let t = child_in_parent(joint, q);
            poses[joint.child] = poses[joint.parent] * t;
            let x = motion_transform(&t);
            let joint_velocity = match (motion_subspace(joint), joint.actuated) {
                (Some(s), Some(a)) => s * self.qd[a],
                _ => Vector6::zeros(),
            };
            let v = x * velocity[joint.parent] + joint_velocity;
            velocity[joint.child] = v;
            passes[k].x = x;
            passes[k].c = cross_motion(&v, &joint_velocity);
        }
        // External forces in each link's coordinates: gravity and, for a free robot, the ground.
        let mut external = vec![Vector6::zeros(); links];
        for (l, inertial) in self.model.inertials().iter().enumerate() {
            let g = poses[l].rotation.inverse() * (gravity * inertial.mass_kg);
            external[l] = spatial(inertial.com_m.cross(&g), g);
        }
        // A point of a link moving with it (world, m/s).
        let velocity_of = |link: usize, point: &Vector3<f64>| {
            let pose = &poses[link];
            let r = pose.rotation.inverse() * (point - pose.translation.vector);
            let v = &velocity[link];
            pose.rotation * (linear(v) + angular(v).cross(&r))
        };
        let mut forces = Vec::new();
        if floating {
            forces = self.contacts.forces(&poses, velocity_of);
        }
        if let Some(self_contacts) = &mut self.self_contacts {
            forces.extend(self_contacts.forces(&poses, velocity_of));
        }
        for f in forces {
            let pose = &poses[f.link];
            let force = pose.rotation.inverse() * f.force_n;
            let r = pose.rotation.inverse() * (f.at_m - pose.translation.vector);
            external[f.link] += spatial(r.cross(&force), force);
        }
        let mut articulated: Vec<Matrix6<f64>> = self.inertia.clone();
        let mut bias: Vec<Vector6<f64>> = (0..links)
            .map(|l| cross_force(&velocity[l], &(self.inertia[l] * velocity[l])) - external[l])
            .collect();

        // Pass 2, leaves to root: articulated inertias and biases.
        for (k, joint) in tree.iter().enumerate().rev() {
            let i = joint.child;
            let pass = &mut passes[k];
            let driven = joint.actuated.filter(|&a| !self.is_follower[a]);
            let (ia, pa) = match (motion_subspace(joint), driven) {
                (Some(s), Some(a)) => {
                    let u_vec = articulated[i] * s;
                    let (force, implicit) = self.joint_terms(a, tau[a], dt);
                    let d = s.dot(&u_vec) + implicit;
                    let u = force - s.dot(&bias[i]);
                    pass.u_vec = u_vec;
                    pass.d = d;
                    pass.u = u;
                    let ia = articulated[i] - u_vec * u_vec.transpose() / d;
                    let pa = bias[i] + ia * pass.c + u_vec * (u / d);
                    (ia, pa)
                }
                _ => (articulated[i], bias[i] + articulated[i] * pass.c),
            };
            let xt = pass.x.transpose();
            articulated[joint.parent] += xt * ia * pass.x;
            bias[joint.parent] += xt * pa;
        }

        // Pass 3, root to leaves: accelerations.
        let mut acceleration = vec![Vector6::zeros(); links];
        if free {
            acceleration[root] = match articulated[root].cholesky() {
                Some(c) => -c.solve(&bias[root]),
                None => Vector6::repeat(f64::NAN),
            };
        }
        let mut qdd = vec![0.0; self.q.len()];
        for (k, joint) in tree.iter().enumerate() {
            let pass = &passes[k];
            let a_prime = pass.x * acceleration[joint.parent] + pass.c;
            let driven = joint.actuated.filter(|&a| !self.is_follower[a]);
            acceleration[joint.child] = match (motion_subspace(joint), driven) {
                (Some(s), Some(a)) => {
                    qdd[a] = (pass.u - pass.u_vec.dot(&a_prime)) / pass.d;
                    a_prime + s * qdd[a]
                }
                _ => a_prime,
            };
        }

        (qdd, acceleration[root])
    }
}
