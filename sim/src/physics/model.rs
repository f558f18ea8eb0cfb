//! An owned kinematic and inertial model of a URDF tree, in `f64`, independent of rapier.
//!
//! It serves three purposes: it carries what rapier3d-urdf ignores (effort and velocity
//! limits, `<dynamics>`, `<mimic>`), it gives the firmware emulators forward kinematics of the
//! URDF links, and it computes gravity torques with our own code, so tests can check the
//! rapier world against an independent reference.

use nalgebra::{DMatrix, Isometry3, Matrix3, Point3, Translation3, UnitQuaternion, Vector3};

use super::error::PhysicsError;

/// Standard gravity along −Z (URDF models are Z-up), m/s².
pub const DEFAULT_GRAVITY_M_S2: [f64; 3] = [0.0, 0.0, -9.81];

/// The kind of an actuated joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the joint axis; positions in rad, velocities in rad/s, efforts in N·m.
    /// URDF `continuous` joints are revolute joints with infinite limits.
    Revolute,
    /// Translation along the joint axis; positions in m, velocities in m/s, efforts in N.
    Prismatic,
}

/// A URDF `<mimic>` relation: `q_self = multiplier · q_leader + offset`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mimic {
    /// Name of the leader joint.
    pub leader: String,
    /// Index of the leader in [`ArmModel::joints`].
    pub leader_index: usize,
    /// Multiplier (dimensionless).
    pub multiplier: f64,
    /// Offset (rad or m, the follower's unit).
    pub offset: f64,
}

/// One actuated (revolute, continuous or prismatic) joint, as read from the URDF.
///
/// Units follow [`JointKind`]: rad / rad/s / N·m for revolute joints, m / m/s / N for prismatic.
#[derive(Debug, Clone, PartialEq)]
pub struct JointInfo {
    /// URDF joint name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Lower position limit (rad or m); −∞ for continuous joints.
    pub lower: f64,
    /// Upper position limit (rad or m); +∞ for continuous joints.
    pub upper: f64,
    /// `limit.effort` (N·m or N). rapier ignores it: the motor model must clamp.
    pub effort_limit: f64,
    /// `limit.velocity` (rad/s or m/s). rapier ignores it: the motor model must enforce it.
    pub velocity_limit: f64,
    /// `<dynamics damping>` (N·m·s/rad or N·s/m), applied as viscous joint damping in the world.
    pub damping: f64,
    /// `<dynamics friction>` (N·m or N), applied as dry joint friction in the world.
    pub friction: f64,
    /// Reflected rotor inertia of the joint's drive (kg·m² or kg): gear ratio² × rotor
    /// inertia. URDF has no element for it, so it is 0 after parsing and set by the emulator
    /// (see [`ArmModel::set_armature`]); it adds to the joint's own diagonal entry of the mass
    /// matrix, like MuJoCo's `armature`.
    pub armature: f64,
    /// `<mimic>`, when this joint follows another one.
    pub mimic: Option<Mimic>,
    /// Name of the parent link.
    pub parent_link: String,
    /// Name of the child link (the link this joint moves).
    pub child_link: String,
}

impl JointInfo {
    /// Whether `value` lies within `[lower, upper]`.
    pub fn within_limits(&self, value: f64) -> bool {
        value >= self.lower && value <= self.upper
    }
}

/// Mass properties of one link, expressed in the link frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkInertial {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass in the link frame, m.
    pub com_m: Vector3<f64>,
    /// Inertia tensor about the COM, axes of the link frame, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
}

/// How a joint of the tree moves its child link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TreeJointKind {
    /// Not at all.
    Fixed,
    /// About its axis.
    Revolute,
    /// Along its axis.
    Prismatic,
}

/// A joint of the tree, actuated or fixed.
#[derive(Debug, Clone)]
pub(crate) struct TreeJoint {
    pub(crate) kind: TreeJointKind,
    /// Parent link (URDF link index).
    pub(crate) parent: usize,
    /// Child link (URDF link index).
    pub(crate) child: usize,
    /// The joint frame in the parent link's frame (URDF `<origin>`).
    pub(crate) origin: Isometry3<f64>,
    /// Unit axis in the joint frame.
    pub(crate) axis: Vector3<f64>,
    /// Index into the actuated joints, `None` for fixed joints.
    pub(crate) actuated: Option<usize>,
}

/// A URDF tree: links, joints and inertials, read once from urdf-rs into owned `f64` data.
#[derive(Debug, Clone)]
pub struct ArmModel {
    name: String,
    link_names: Vec<String>,
    inertials: Vec<LinkInertial>,
    root: usize,
    /// Joints ordered from the root to the leaves (a parent link's joint comes first).
    tree: Vec<TreeJoint>,
    joints: Vec<JointInfo>,
    /// URDF index of each actuated joint.
    urdf_joint_index: Vec<usize>,
    /// For each link, the index in `tree` of the joint that moves it (`None` for the root).
    parent_joint: Vec<Option<usize>>,
    /// For each link, the actuated joints between the root and it: built on the first
    /// gravity-torque or mass-matrix call (the arms' firmware asks every 1 ms) and kept, not
    /// at load (a 5,000-link chain's lists would take 100 MB, and robots never ask).
    ancestors: std::sync::OnceLock<Vec<Vec<usize>>>,
}

fn pose_to_isometry(pose: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = pose.xyz.0;
    let [roll, pitch, yaw] = pose.rpy.0;
    // URDF rpy are fixed-axis X, Y, Z: R = Rz(yaw)·Ry(pitch)·Rx(roll), which is nalgebra's
    // `from_euler_angles(roll, pitch, yaw)`.
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

fn inertial_of(link: &urdf_rs::Link) -> Result<LinkInertial, PhysicsError> {
    let inertial = &link.inertial;
    let i = &inertial.inertia;
    let values = [
        inertial.mass.value,
        i.ixx,
        i.ixy,
        i.ixz,
        i.iyy,
        i.iyz,
        i.izz,
    ];
    let frame = inertial.origin.xyz.0.iter().chain(&inertial.origin.rpy.0);
    if values.iter().chain(frame).any(|v| !v.is_finite()) {
        return Err(PhysicsError::InvalidInertial {
            link: link.name.clone(),
            reason: "non-finite value".to_owned(),
        });
    }
    if inertial.mass.value < 0.0 {
        return Err(PhysicsError::InvalidInertial {
            link: link.name.clone(),
            reason: format!("negative mass {}", inertial.mass.value),
        });
    }
    let origin = pose_to_isometry(&inertial.origin);
    let tensor = Matrix3::new(
        i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
    );
    // The tensor is given in the inertial frame; bring it to the link frame axes.
    let rot = origin.rotation.to_rotation_matrix();
    let tensor = rot.matrix() * tensor * rot.matrix().transpose();
    Ok(LinkInertial {
        mass_kg: inertial.mass.value,
        com_m: origin.translation.vector,
        inertia_kg_m2: tensor,
    })
}

impl ArmModel {
    /// Parses URDF text into a model.
    pub fn from_urdf_str(xml: &str) -> Result<Self, PhysicsError> {
        let robot = urdf_rs::read_from_string(xml).map_err(|e| PhysicsError::Parse {
            message: e.to_string(),
        })?;
        Self::from_robot(&robot)
    }

    /// Reads and parses a URDF file into a model (at most [`MAX_URDF_BYTES`]).
    pub fn from_urdf_file(path: &std::path::Path) -> Result<Self, PhysicsError> {
        Self::from_urdf_str(&read_urdf(path)?)
    }

    /// Builds the model from an already parsed urdf-rs robot.
    ///
    /// Actuated joints are the revolute, continuous and prismatic joints, in URDF document
    /// order. Fixed joints are kept in the tree; floating, planar and spherical joints are
    /// rejected.
    pub fn from_robot(robot: &urdf_rs::Robot) -> Result<Self, PhysicsError> {
        let link_names: Vec<String> = robot.links.iter().map(|l| l.name.clone()).collect();
        // By name, once: a 5,000-link URDF must not cost a scan per joint.
        let by_name: std::collections::HashMap<&str, usize> = link_names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect();
        let link_index = |joint: &str, name: &str| {
            by_name
                .get(name)
                .copied()
                .ok_or_else(|| PhysicsError::UnknownLink {
                    joint: joint.to_owned(),
                    link: name.to_owned(),
                })
        };
        let inertials = robot
            .links
            .iter()
            .map(inertial_of)
            .collect::<Result<Vec<_>, _>>()?;

        let mut raw = Vec::with_capacity(robot.joints.len());
        let mut joints = Vec::new();
        let mut urdf_joint_index = Vec::new();
        for (u, j) in robot.joints.iter().enumerate() {
            let parent = link_index(&j.name, &j.parent.link)?;
            let child = link_index(&j.name, &j.child.link)?;
            let (kind, jkind, lower, upper) = match j.joint_type {
                urdf_rs::JointType::Fixed => (TreeJointKind::Fixed, None, 0.0, 0.0),
                urdf_rs::JointType::Revolute => (
                    TreeJointKind::Revolute,
                    Some(JointKind::Revolute),
                    j.limit.lower,
                    j.limit.upper,
                ),
                urdf_rs::JointType::Continuous => (
                    TreeJointKind::Revolute,
                    Some(JointKind::Revolute),
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                ),
                urdf_rs::JointType::Prismatic => (
                    TreeJointKind::Prismatic,
                    Some(JointKind::Prismatic),
                    j.limit.lower,
                    j.limit.upper,
                ),
                ref other => {
                    return Err(PhysicsError::UnsupportedJoint {
                        joint: j.name.clone(),
                        kind: format!("{other:?}"),
                    })
                }
            };
            // What `description::checks` refuses with a line number, refused here too for
            // callers that build a model from text directly: a NaN limit panics a clamp later.
            if matches!(kind, TreeJointKind::Revolute | TreeJointKind::Prismatic)
                && (lower.is_nan() || upper.is_nan() || lower > upper)
            {
                return Err(PhysicsError::InvalidLimits {
                    joint: j.name.clone(),
                    lower,
                    upper,
                });
            }
            let frame = j
                .origin
                .xyz
                .0
                .iter()
                .chain(&j.origin.rpy.0)
                .chain(&j.axis.xyz.0);
            if frame.into_iter().any(|v| !v.is_finite()) {
                return Err(PhysicsError::NonFiniteFrame {
                    joint: j.name.clone(),
                });
            }
            let axis = Vector3::from(j.axis.xyz.0);
            let axis = match kind {
                TreeJointKind::Fixed => Vector3::z(),
                _ => axis
                    .try_normalize(1e-12)
                    .ok_or_else(|| PhysicsError::ZeroAxis {
                        joint: j.name.clone(),
                    })?,
            };
            let actuated = jkind.map(|kind| {
                let (damping, friction) = j
                    .dynamics
                    .as_ref()
                    .map_or((0.0, 0.0), |d| (d.damping, d.friction));
                joints.push(JointInfo {
                    name: j.name.clone(),
                    kind,
                    lower,
                    upper,
                    effort_limit: j.limit.effort,
                    velocity_limit: j.limit.velocity,
                    damping,
                    friction,
                    armature: 0.0,
                    mimic: None,
                    parent_link: j.parent.link.clone(),
                    child_link: j.child.link.clone(),
                });
                urdf_joint_index.push(u);
                joints.len() - 1
            });
            raw.push(TreeJoint {
                kind,
                parent,
                child,
                origin: pose_to_isometry(&j.origin),
                axis,
                actuated,
            });
        }

        // Mimic leaders can only be resolved once every actuated joint is known.
        for (u, j) in robot.joints.iter().enumerate() {
            let (Some(m), Some(a)) = (&j.mimic, raw[u].actuated) else {
                continue;
            };
            let leader_index =
                joints
                    .iter()
                    .position(|ji| ji.name == m.joint)
                    .ok_or_else(|| PhysicsError::UnknownMimicLeader {
                        joint: j.name.clone(),
                        leader: m.joint.clone(),
                    })?;
            joints[a].mimic = Some(Mimic {
                leader: m.joint.clone(),
                leader_index,
                multiplier: m.multiplier.unwrap_or(1.0),
                offset: m.offset.unwrap_or(0.0),
            });
        }

        // One tree: exactly one link without a parent joint, each other link exactly one.
        let mut parent_count = vec![0usize; link_names.len()];
        for j in &raw {
            parent_count[j.child] += 1;
        }
        let roots: Vec<usize> = (0..link_names.len())
            .filter(|&l| parent_count[l] == 0)
            .collect();
        let not_a_tree = || PhysicsError::NotATree {
            roots: roots.iter().map(|&l| link_names[l].clone()).collect(),
        };
        if roots.len() != 1 || parent_count.iter().any(|&c| c > 1) {
            return Err(not_a_tree());
        }
        let root = roots[0];

        // Order joints root → leaves with an explicit stack (deterministic: URDF order).
        let mut children = vec![Vec::new(); link_names.len()];
        for (u, j) in raw.iter().enumerate() {
            children[j.parent].push(u);
        }
        let mut tree = Vec::with_capacity(raw.len());
        let mut parent_joint = vec![None; link_names.len()];
        let mut reached = vec![false; link_names.len()];
        reached[root] = true;
        let mut stack = vec![root];
        while let Some(link) = stack.pop() {
            for &u in &children[link] {
                let j = &raw[u];
                parent_joint[j.child] = Some(tree.len());
                reached[j.child] = true;
                tree.push(j.clone());
                stack.push(j.child);
            }
        }
        if reached.iter().any(|r| !r) {
            return Err(not_a_tree());
        }

        Ok(Self {
            name: robot.name.clone(),
            link_names,
            inertials,
            root,
            tree,
            joints,
            urdf_joint_index,
            parent_joint,
            ancestors: std::sync::OnceLock::new(),
        })
    }

    /// The link whose joint carries link `link` (URDF link indices); `None` for the root.
    pub(crate) fn parent_link(&self, link: usize) -> Option<usize> {
        self.parent_joint
            .get(link)
            .copied()
            .flatten()
            .map(|k| self.tree[k].parent)
    }

    /// Per link, the actuated joints between the root and it, nearest the root first.
    fn ancestors(&self) -> &[Vec<usize>] {
        self.ancestors.get_or_init(|| {
            (0..self.link_names.len())
                .map(|link| {
                    let mut chain = Vec::new();
                    let mut at = self.parent_joint[link];
                    while let Some(k) = at {
                        let joint = &self.tree[k];
                        chain.extend(joint.actuated);
                        at = self.parent_joint[joint.parent];
                    }
                    chain.reverse();
                    chain
                })
                .collect()
        })
    }

    /// The joints from the root to the leaves (a parent link's joint before its children's).
    pub(crate) fn tree(&self) -> &[TreeJoint] {
        &self.tree
    }

    /// The root link (URDF link index): the one link no joint moves.
    pub(crate) fn root_link(&self) -> usize {
        self.root
    }

    /// The root link's name: the robot's base, whichever place the URDF lists it in.
    pub fn root_link_name(&self) -> &str {
        &self.link_names[self.root]
    }

    /// The robot's name (`<robot name>`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The actuated joints, in URDF document order.
    pub fn joints(&self) -> &[JointInfo] {
        &self.joints
    }

    /// Index of the actuated joint called `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Sets the reflected rotor inertia of actuated joint `joint` (kg·m² or kg). Negative or
    /// non-finite values are taken as 0; an unknown index is ignored.
    pub fn set_armature(&mut self, joint: usize, armature: f64) {
        if let Some(j) = self.joints.get_mut(joint) {
            j.armature = if armature.is_finite() {
                armature.max(0.0)
            } else {
                0.0
            };
        }
    }

    /// URDF `<joint>` index (document order among all joints) of each actuated joint.
    pub fn urdf_joint_indices(&self) -> &[usize] {
        &self.urdf_joint_index
    }

    /// All link names, in URDF document order.
    pub fn link_names(&self) -> &[String] {
        &self.link_names
    }

    /// Index of the link called `name`.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.link_names.iter().position(|l| l == name)
    }

    /// The mass properties of each link, in URDF document order.
    pub fn inertials(&self) -> &[LinkInertial] {
        &self.inertials
    }

    /// Total mass of the links that can move (every link except the root), kg.
    pub fn moving_mass_kg(&self) -> f64 {
        self.inertials
            .iter()
            .enumerate()
            .filter(|(l, _)| *l != self.root)
            .map(|(_, i)| i.mass_kg)
            .sum()
    }

    fn check_len(&self, q: &[f64]) -> Result<(), PhysicsError> {
        if q.len() != self.joints.len() {
            return Err(PhysicsError::LengthMismatch {
                expected: self.joints.len(),
                actual: q.len(),
            });
        }
        if let Some((i, v)) = q.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(PhysicsError::NonFinite {
                joint: self.joints[i].name.clone(),
                value: *v,
            });
        }
        Ok(())
    }

    /// Pose of every link frame in the root frame at joint positions `q` (one value per
    /// actuated joint, rad or m), in URDF link order. The root link is at the identity.
    pub fn link_poses(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, PhysicsError> {
        self.check_len(q)?;
        let mut poses = vec![Isometry3::identity(); self.link_names.len()];
        for j in &self.tree {
            let motion = match (j.kind, j.actuated) {
                (TreeJointKind::Revolute, Some(a)) => Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_scaled_axis(j.axis * q[a]),
                ),
                (TreeJointKind::Prismatic, Some(a)) => Isometry3::from_parts(
                    Translation3::from(j.axis * q[a]),
                    UnitQuaternion::identity(),
                ),
                _ => Isometry3::identity(),
            };
            poses[j.child] = poses[j.parent] * j.origin * motion;
        }
        Ok(poses)
    }

    /// Pose of the link called `link` in the root frame at joint positions `q`.
    pub fn link_pose(&self, link: &str, q: &[f64]) -> Result<Option<Isometry3<f64>>, PhysicsError> {
        let Some(l) = self.link_index(link) else {
            return Ok(None);
        };
        Ok(Some(self.link_poses(q)?[l]))
    }

    /// Joint torques (N·m) / forces (N) the motors must produce to hold the model still at `q`
    /// against `gravity_m_s2`, one per actuated joint.
    ///
    /// Computed by Jacobian transpose from the URDF inertials, with no rapier involved:
    /// `τ_j = −Σ_l m_l g · (a_j × (c_l − p_j))` over the links `l` moved by revolute joint `j`
    /// (axis `a_j` through `p_j`, link COM `c_l`), `τ_j = −Σ_l m_l g · a_j` for a prismatic joint.
    /// Mimic joints are treated as independent joints (each gets the torque that holds its own
    /// subtree).
    pub fn gravity_torques(
        &self,
        q: &[f64],
        gravity_m_s2: [f64; 3],
    ) -> Result<Vec<f64>, PhysicsError> {
        let poses = self.link_poses(q)?;
        let ancestors = self.ancestors();
        let g = Vector3::from(gravity_m_s2);
        let mut tau = vec![0.0; self.joints.len()];
        for j in &self.tree {
            let Some(a) = j.actuated else { continue };
            let joint_frame = poses[j.parent] * j.origin;
            let axis_w = joint_frame.rotation * j.axis;
            let pivot_w = joint_frame.translation.vector;
            for (l, inertial) in self.inertials.iter().enumerate() {
                if !ancestors[l].contains(&a) {
                    continue;
                }
                let weight = g * inertial.mass_kg;
                let generalized = match j.kind {
                    TreeJointKind::Revolute => {
                        let com_w = poses[l] * Point3::from(inertial.com_m);
                        axis_w.cross(&(com_w.coords - pivot_w)).dot(&weight)
                    }
                    _ => axis_w.dot(&weight),
                };
                tau[a] -= generalized;
            }
        }
        Ok(tau)
    }

    /// The joint-space mass matrix at `q` (n × n over the actuated joints; kg·m², kg·m or kg
    /// depending on the joint kinds): `M = Σ_l m_l·J_v,lᵀ·J_v,l + J_ω,lᵀ·I_l·J_ω,l` over the
    /// links, with `J_v,l`, `J_ω,l` the Jacobians of link `l`'s COM and `I_l` its inertia
    /// about the COM in world axes, plus each joint's [`JointInfo::armature`] on its diagonal.
    /// Motor controllers use it to decouple the joints. Mimic
    /// followers are treated as independent joints.
    pub fn mass_matrix(&self, q: &[f64]) -> Result<DMatrix<f64>, PhysicsError> {
        let poses = self.link_poses(q)?;
        let n = self.joints.len();
        // Axis and pivot of every actuated joint in the world.
        let mut axes = vec![(TreeJointKind::Fixed, Vector3::zeros(), Vector3::zeros()); n];
        for j in &self.tree {
            if let Some(a) = j.actuated {
                let frame = poses[j.parent] * j.origin;
                axes[a] = (j.kind, frame.rotation * j.axis, frame.translation.vector);
            }
        }
        let mut m = DMatrix::zeros(n, n);
        for (l, inertial) in self.inertials.iter().enumerate() {
            let com_w = (poses[l] * Point3::from(inertial.com_m)).coords;
            let rot = poses[l].rotation.to_rotation_matrix();
            let inertia_w = rot.matrix() * inertial.inertia_kg_m2 * rot.matrix().transpose();
            let mut jv = DMatrix::zeros(3, n);
            let mut jw = DMatrix::zeros(3, n);
            for &a in &self.ancestors()[l] {
                let (kind, axis, pivot) = axes[a];
                let (lin, ang) = match kind {
                    TreeJointKind::Revolute => (axis.cross(&(com_w - pivot)), axis),
                    _ => (axis, Vector3::zeros()),
                };
                jv.set_column(a, &lin);
                jw.set_column(a, &ang);
            }
            m += jv.transpose() * &jv * inertial.mass_kg + jw.transpose() * inertia_w * &jw;
        }
        for (a, joint) in self.joints.iter().enumerate() {
            m[(a, a)] += joint.armature;
        }
        Ok(m)
    }

    /// Diagonal of [`ArmModel::mass_matrix`]: the inertia (kg·m², revolute) or mass (kg,
    /// prismatic) a joint's motor drives when the other joints are held still.
    pub fn mass_matrix_diagonal(&self, q: &[f64]) -> Result<Vec<f64>, PhysicsError> {
        Ok(self.mass_matrix(q)?.diagonal().iter().copied().collect())
    }
}

/// Largest URDF file read, bytes: 16 MiB. The bundled models are under 20 KB and meshes are
/// never read; the bound stops a mistyped path to a device or a multi-GB file from being read
/// whole into memory.
pub const MAX_URDF_BYTES: u64 = 16 * 1024 * 1024;

/// The text of the URDF file `path`: a regular file of at most [`MAX_URDF_BYTES`], UTF-8.
pub fn read_urdf(path: &std::path::Path) -> Result<String, PhysicsError> {
    use crate::bounded_read::{read_regular_file, BoundedReadError};
    let fail = |source| PhysicsError::Io {
        path: path.to_owned(),
        source,
    };
    let refuse = |why: &str| fail(std::io::Error::new(std::io::ErrorKind::InvalidData, why));
    let bytes = read_regular_file(path, MAX_URDF_BYTES).map_err(|error| match error {
        BoundedReadError::NotAFile => refuse("not a regular file"),
        BoundedReadError::TooLarge { .. } => {
            refuse("larger than 16 MiB, the limit for a URDF file")
        }
        BoundedReadError::Io(source) => fail(source),
    })?;
    String::from_utf8(bytes).map_err(|_| refuse("stream did not contain valid UTF-8"))
}
