//! Errors of the physics world and of the URDF model.

use std::path::PathBuf;

/// Everything that can go wrong while loading a URDF model or driving the physics world.
#[derive(Debug, thiserror::Error)]
pub enum PhysicsError {
    /// The URDF file could not be read.
    #[error("cannot read URDF file {path}: {source}")]
    Io {
        /// The file that was asked for.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The URDF text is not valid URDF (XML or schema error reported by urdf-rs).
    #[error("invalid URDF: {message}")]
    Parse {
        /// The parser's message.
        message: String,
    },
    /// A joint type the world does not simulate (floating, planar, spherical).
    #[error("joint {joint}: unsupported joint type {kind}")]
    UnsupportedJoint {
        /// The joint's name.
        joint: String,
        /// The URDF joint type.
        kind: String,
    },
    /// A joint names a parent or child link that the URDF does not define.
    #[error("joint {joint}: unknown link {link}")]
    UnknownLink {
        /// The joint's name.
        joint: String,
        /// The missing link's name.
        link: String,
    },
    /// A `<mimic>` element names a joint that is not a revolute or prismatic joint of the model.
    #[error("joint {joint}: its <mimic> leader `{leader}` is not a movable joint of the URDF (no such revolute, continuous or prismatic joint)")]
    UnknownMimicLeader {
        /// The follower joint.
        joint: String,
        /// The leader it names.
        leader: String,
    },
    /// The links do not form one tree with a single root.
    #[error("URDF links do not form a single tree (roots: {roots:?})")]
    NotATree {
        /// The links that have no parent joint.
        roots: Vec<String>,
    },
    /// Joint limits that are not finite or the wrong way round.
    #[error("joint {joint}: limits [{lower}, {upper}] are not a range")]
    InvalidLimits {
        /// The joint's name.
        joint: String,
        /// Lower limit as given.
        lower: f64,
        /// Upper limit as given.
        upper: f64,
    },
    /// A joint's origin or axis holds a number that is not finite.
    #[error("joint {joint}: its origin or axis is not finite")]
    NonFiniteFrame {
        /// The joint's name.
        joint: String,
    },
    /// A joint that moves nothing with mass or inertia about its axis: the physics cannot
    /// accelerate it (links with no inertial at the end of a chain).
    #[error("joint {joint} moves nothing with mass or inertia about its axis (its links have no <inertial>); the physics cannot accelerate it")]
    MasslessJoint {
        /// The joint's name.
        joint: String,
    },
    /// The solver cannot do what was asked of it.
    #[error("this physics solver does not support {what}")]
    Unsupported {
        /// What was asked.
        what: String,
    },
    /// A joint axis of zero length.
    #[error("joint {joint}: axis has zero length")]
    ZeroAxis {
        /// The joint's name.
        joint: String,
    },
    /// An inertial element is not physical (negative mass or a non-finite value).
    #[error("link {link}: invalid inertial ({reason})")]
    InvalidInertial {
        /// The link's name.
        link: String,
        /// What is wrong.
        reason: String,
    },
    /// A per-joint vector has the wrong length.
    #[error("expected {expected} joint values, got {actual}")]
    LengthMismatch {
        /// Number of actuated joints of the model.
        expected: usize,
        /// Length that was passed.
        actual: usize,
    },
    /// A joint position outside the joint's URDF limits.
    #[error("joint {joint}: {value} outside limits [{lower}, {upper}]")]
    OutOfLimit {
        /// The joint's name.
        joint: String,
        /// The rejected value (rad or m).
        value: f64,
        /// Lower limit (rad or m).
        lower: f64,
        /// Upper limit (rad or m).
        upper: f64,
    },
    /// A NaN or infinite joint value.
    #[error("joint {joint}: non-finite value {value}")]
    NonFinite {
        /// The joint's name.
        joint: String,
        /// The rejected value.
        value: f64,
    },
    /// The world configuration is unusable (non-positive or non-finite step, non-finite gravity).
    #[error("invalid world configuration: {reason}")]
    InvalidConfig {
        /// What is wrong.
        reason: String,
    },
    /// The simulated state stopped being finite (a torque or force far beyond what the
    /// model can take): the world's state is NaN from then on and must not be read as a pose.
    #[error(
        "the physics diverged: joint {joint} has a non-finite position or velocity since t = {time_s:.3} s (a torque or force far beyond the model's limits)"
    )]
    Diverged {
        /// The first joint found non-finite.
        joint: String,
        /// Simulated time of the step that diverged, s.
        time_s: f64,
    },
    /// rapier did not create a multibody joint for an actuated URDF joint (for example a joint
    /// that would close a kinematic loop).
    #[error("joint {joint}: not represented in the rapier multibody")]
    NotInMultibody {
        /// The joint's name.
        joint: String,
    },
}

/// Where and when a world's state first stopped being finite, kept for good: a diverged
/// world does not recover, and its owner must report it instead of reading its NaNs. Both
/// physics worlds (rapier's and the articulated one) hold one.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Divergence(Option<(String, f64)>);

impl Divergence {
    /// Whether the state has stopped being finite.
    pub(crate) fn happened(&self) -> bool {
        self.0.is_some()
    }

    /// Remember `joint` at `time_s` as the first non-finite state.
    pub(crate) fn record(&mut self, joint: String, time_s: f64) {
        self.0 = Some((joint, time_s));
    }

    /// `Ok` while the state is finite, then [`PhysicsError::Diverged`] naming the first joint.
    pub(crate) fn check(&self) -> Result<(), PhysicsError> {
        match &self.0 {
            None => Ok(()),
            Some((joint, time_s)) => Err(PhysicsError::Diverged {
                joint: joint.clone(),
                time_s: *time_s,
            }),
        }
    }
}
