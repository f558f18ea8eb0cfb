//! A robot file as written (layer 1): every value with its place in the file.

use serde::Deserialize;

/// A value with its place in the file.
pub(super) type S<T> = serde_saphyr::Spanned<T>;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRobot {
    /// The robot's name.
    pub robot: S<String>,
    /// The URDF, relative to the robot file.
    pub urdf: S<String>,
    /// ROS packages the URDF's `package://` names point into: name → folder (relative to
    /// the robot file); searched before `ROS_PACKAGE_PATH` and `AMENT_PREFIX_PATH`.
    pub packages: Option<S<std::collections::BTreeMap<String, S<String>>>>,
    /// Links touching links: `true`, or the pairs of links to leave out (`[[a, b], …]`);
    /// off when left out or `false`.
    pub self_collision: Option<S<RawSelfCollision>>,
    /// Links whose collision meshes are split into convex parts (for `self_collision`).
    pub convex_decomposition: Option<S<Vec<S<String>>>>,
    /// `refuse` (default) or `skip`: what a collision mesh that cannot be found does.
    pub missing_meshes: Option<S<String>>,
    /// `fixed` (default) or `floating`.
    pub base: Option<S<String>>,
    /// Floating base: `off` (default), `until_enabled` or `until_released`.
    pub gantry: Option<S<String>>,
    /// The solver: `articulated` (default) or `rapier`.
    pub physics: Option<S<String>>,
    /// Floating base: the root link's height above the ground at start (m).
    pub start_height_m: Option<S<f64>>,
    /// The buses.
    pub buses: S<Vec<S<RawBus>>>,
    /// The actuated joints.
    pub actuators: S<Vec<S<RawActuator>>>,
    /// Joint positions at start (rad), as a list of one-key mappings in file order.
    pub start_rad: Option<S<Vec<S<RawStart>>>>,
}

/// `self_collision:` as written.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(super) enum RawSelfCollision {
    /// On (`true`) or off (`false`).
    Switch(bool),
    /// On, leaving these pairs of links out.
    Except(Vec<[S<String>; 2]>),
}

/// One bus.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBus {
    /// `can0` …: also the SocketCAN interface and the socketcand channel it is served on.
    pub name: S<String>,
    /// Bit rate (bit/s); 1 Mbit/s when left out.
    pub bitrate: Option<S<i64>>,
    /// CAN FD's data-phase bit rate (bit/s): the bus runs CAN FD. Classic when left out.
    pub data_bitrate: Option<S<i64>>,
}

/// One actuated joint.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawActuator {
    /// The URDF joint.
    pub joint: S<String>,
    /// RobStride model (`RS03` …).
    pub model: S<String>,
    /// CAN id (1..=127).
    pub id: S<i64>,
    /// The bus's name.
    pub bus: S<String>,
    /// +1 or −1; +1 when left out.
    pub direction: Option<S<i64>>,
    /// Joint position at which the shaft reads 0 (rad); 0 when left out.
    pub zero_offset_rad: Option<S<f64>>,
}

/// One start position: `{joint: knee, rad: 0.3}`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStart {
    /// The URDF joint.
    pub joint: S<String>,
    /// Its position (rad).
    pub rad: S<f64>,
}
