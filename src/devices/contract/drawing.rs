//! What the 3D views need of a kind: the URDF it is drawn from and how a run's trace poses it.

use std::borrow::Cow;

/// How the 3D views (report replay, live page) draw a device.
#[derive(Debug, Clone, PartialEq)]
pub struct Drawing {
    /// The URDF text: a bundled model, or the robot file's URDF read when the scenario loaded.
    pub urdf: Cow<'static, str>,
    /// Which trace columns pose it.
    pub posed_by: Posing,
    /// Where the files the URDF names (meshes) are: a robot's `urdf_paths`; `None` for a
    /// bundled model (no meshes, or only absolute names).
    pub paths: Option<sim::description::PackagePaths>,
}

/// Which trace columns give the drawn model its pose.
#[derive(Debug, Clone, PartialEq)]
pub enum Posing {
    /// An arm's columns: `j1_deg`… for the URDF's revolute joints in document order and
    /// `gripper_mm` for its fingers (each travels half).
    ArmColumns,
    /// Named URDF joints, each from its own column, and a floating root link from the base
    /// columns the trace holds (any it lacks count as 0: upright at the origin).
    Joints {
        /// One per traced joint.
        joints: Vec<JointColumn>,
        /// The root link's pose columns, for a floating base.
        base: Option<BaseColumns>,
    },
}

/// One URDF joint posed from one trace column: `q = direction · value + offset_rad`.
#[derive(Debug, Clone, PartialEq)]
pub struct JointColumn {
    /// The trace column.
    pub column: String,
    /// The URDF joint.
    pub joint: String,
    /// +1 or −1: the actuator's sense against the joint's.
    pub direction: f64,
    /// The joint's position at a traced 0 (rad).
    pub offset_rad: f64,
}

/// The trace columns of a floating root link's pose: position (m) and URDF roll, pitch, yaw
/// (rad).
#[derive(Debug, Clone, PartialEq)]
pub struct BaseColumns {
    /// x, y, z of the root link's origin.
    pub position_m: [&'static str; 3],
    /// Roll, pitch, yaw.
    pub rpy_rad: [&'static str; 3],
}

impl Drawing {
    /// A bundled arm model posed by the arm columns.
    pub fn arm(urdf: &'static str) -> Self {
        Self {
            urdf: Cow::Borrowed(urdf),
            posed_by: Posing::ArmColumns,
            paths: None,
        }
    }
}
