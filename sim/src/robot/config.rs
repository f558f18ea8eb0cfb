//! What a robot is made of, as the emulator takes it: plain data, checked by
//! [`RobotConfig::check`]. Robot files (YAML with positions for errors) are read into this by
//! the `armhil` crate.

use std::path::PathBuf;

use std::sync::Arc;

use crate::actuator::ActuatorConfig;
use crate::description::{CollisionGeometry, MissingMeshes, PackagePaths};
use crate::physics::Solver;

/// How the robot's root link meets the world.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Base {
    /// Bolted down: the URDF root link does not move (an arm on a table).
    #[default]
    Fixed,
    /// Free: the root link is a free body above a ground plane at z = 0, which the links'
    /// collision shapes stand on; a robot whose actuators let go falls.
    Floating {
        /// Height of the root link's origin above the ground at start (m).
        start_height_m: f64,
    },
}

/// A stand holding a floating robot's base where it starts, as a humanoid hangs on a gantry
/// during bring-up: the joints move, the base does not, until the stand lets go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Gantry {
    /// No stand: the base is free from the start (a robot that is not held up falls).
    #[default]
    Off,
    /// Held until every actuator is enabled (each for the first time; the stand does not
    /// come back), or until released.
    UntilEnabled,
    /// Held until released, never on its own (a scenario's `group: {do: release_gantry}`,
    /// the web view's `gantry_release`, Python's `inject("gantry_release")`): a robot on its
    /// stand, legs in the air, for as long as the user wants.
    UntilReleased,
}

impl Gantry {
    /// Every gantry as robot files and `armhil sim robot --gantry` write it.
    pub const WORDS: [(&'static str, Gantry); 3] = [
        ("off", Gantry::Off),
        ("until_enabled", Gantry::UntilEnabled),
        ("until_released", Gantry::UntilReleased),
    ];

    /// The gantry written `word`.
    pub fn named(word: &str) -> Option<Self> {
        Self::WORDS
            .iter()
            .find(|(w, _)| *w == word)
            .map(|(_, g)| *g)
    }

    /// The gantry written `word`, or what is wrong with it (`must be one of …, got `x``,
    /// with the nearest word): one message for robot files, scenarios, the CLI and Python,
    /// each of which names its own key before it.
    pub fn parse(word: &str) -> Result<Self, String> {
        Self::named(word).ok_or_else(|| {
            let words: Vec<&str> = Self::WORDS.iter().map(|(w, _)| *w).collect();
            format!(
                "must be one of {}, got `{word}`{}",
                words.join(", "),
                crate::yaml_words::suggestion(word, &words)
            )
        })
    }

    /// How robot files write it.
    pub fn word(self) -> &'static str {
        Self::WORDS
            .iter()
            .find(|(_, g)| *g == self)
            .map_or("off", |(w, _)| w)
    }
}

/// One CAN bus of the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct BusConfig {
    /// Its name (`can0` …): the interface or socketcand channel it is served on.
    pub name: String,
    /// Bit rate (bit/s): the arbitration phase's, for CAN FD.
    pub bitrate_bps: u32,
    /// CAN FD's data-phase bit rate (bit/s) when the bus runs CAN FD (the OpenArm's: 1 and
    /// 5 Mbit/s); `None`: classic CAN.
    pub data_bitrate_bps: Option<u32>,
}

/// An actuated joint: which motor drives it, on which bus, and how the shaft meets the joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointActuator {
    /// The URDF joint (revolute or continuous).
    pub joint: String,
    /// Index into [`RobotConfig::buses`].
    pub bus: usize,
    /// The actuator: its kind and model, CAN id and firmware settings (any kind the
    /// actuator registry lists, [`crate::actuator::KINDS`]).
    pub actuator: ActuatorConfig,
    /// +1 when the shaft turns the joint's positive way, −1 when mounted the other way round.
    pub direction: f64,
    /// Joint position (rad) at which the shaft reads 0.
    pub zero_offset_rad: f64,
}

/// A whole robot: its URDF, base, buses and actuators.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotConfig {
    /// The robot's name (for logs and views).
    pub name: String,
    /// The URDF text.
    pub urdf: String,
    /// Where the files the URDF names (meshes) are looked for.
    pub urdf_paths: PackagePaths,
    /// What a collision mesh that cannot be found or read does.
    pub missing_meshes: MissingMeshes,
    /// Links touching links (off when `None`): the pairs of link names left out besides
    /// those a joint joins and those that overlap as the robot starts.
    pub self_collision: Option<Vec<(String, String)>>,
    /// Links whose collision meshes are split into convex parts for `self_collision`.
    pub convex_decomposition: Vec<String>,
    /// The collision geometry when already read (a robot file reads it while checking);
    /// `None`: read from the URDF when the world is built.
    pub collision: Option<Arc<CollisionGeometry>>,
    /// Fixed or floating base.
    pub base: Base,
    /// A floating base's stand at start (ignored for a fixed base).
    pub gantry: Gantry,
    /// The solver stepping its world (the articulated-body solver unless the file says).
    pub physics: Solver,
    /// The buses.
    pub buses: Vec<BusConfig>,
    /// The actuated joints; joints not listed are passive.
    pub actuators: Vec<JointActuator>,
    /// Joint positions at start (rad), by URDF joint name; unnamed joints start at 0. A start
    /// outside the joint's limits starts at the nearest limit (robot files warn about it).
    pub start_positions_rad: Vec<(String, f64)>,
    /// Where the actuators' flash (saved parameters, ids, zeros) lives across restarts.
    pub state_file: Option<PathBuf>,
    /// Host ID the motors answer to until a host speaks.
    pub host_id: u8,
}

/// A robot configuration that cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RobotConfigError {
    /// An actuator names a bus that is not there.
    #[error("joint `{joint}`: bus index {bus} is not one of the robot's {buses} buses")]
    UnknownBus {
        /// The joint.
        joint: String,
        /// The index.
        bus: usize,
        /// How many buses there are.
        buses: usize,
    },
    /// Two actuators answer to one CAN id on one bus.
    #[error("joints `{first}` and `{second}` both use CAN id {can_id} on bus `{bus}`")]
    DuplicateCanId {
        /// The bus.
        bus: String,
        /// The id.
        can_id: u32,
        /// The first joint with it.
        first: String,
        /// The second one.
        second: String,
    },
    /// Two actuators drive one joint.
    #[error("joint `{joint}` has two actuators")]
    JointTwice {
        /// The joint.
        joint: String,
    },
    /// A CAN id outside what its kind takes (RobStride: 1..=127).
    #[error(
        "joint `{joint}`: CAN id {can_id} is outside {low}..={high}, the ids of a {kind} actuator"
    )]
    InvalidCanId {
        /// The joint.
        joint: String,
        /// The id.
        can_id: u32,
        /// The kind.
        kind: &'static str,
        /// The lowest id it takes.
        low: u32,
        /// The highest.
        high: u32,
    },
    /// A non-finite or non-positive number where one is needed.
    #[error("{what} must be finite{positive}, got {value}", positive = if *.positive { " and positive" } else { "" })]
    BadNumber {
        /// Which value.
        what: String,
        /// The value.
        value: f64,
        /// Whether it must be positive.
        positive: bool,
    },
}

impl RobotConfig {
    /// Checks what does not need the URDF: bus references, ids, numbers. (Joint names and
    /// the URDF itself are checked when the world loads.)
    pub fn check(&self) -> Result<(), RobotConfigError> {
        let finite = |what: String, value: f64, positive: bool| {
            if value.is_finite() && (!positive || value > 0.0) {
                Ok(())
            } else {
                Err(RobotConfigError::BadNumber {
                    what,
                    value,
                    positive,
                })
            }
        };
        if let Base::Floating { start_height_m } = self.base {
            finite("base start height".into(), start_height_m, false)?;
        }
        for (i, a) in self.actuators.iter().enumerate() {
            if a.bus >= self.buses.len() {
                return Err(RobotConfigError::UnknownBus {
                    joint: a.joint.clone(),
                    bus: a.bus,
                    buses: self.buses.len(),
                });
            }
            let kind = a.actuator.kind();
            let (low, high) = kind.ids;
            if !(low..=high).contains(&a.actuator.can_id()) {
                return Err(RobotConfigError::InvalidCanId {
                    joint: a.joint.clone(),
                    can_id: a.actuator.can_id(),
                    kind: kind.name,
                    low,
                    high,
                });
            }
            finite(
                format!("joint `{}` zero offset", a.joint),
                a.zero_offset_rad,
                false,
            )?;
            for b in &self.actuators[..i] {
                if b.joint == a.joint {
                    return Err(RobotConfigError::JointTwice {
                        joint: a.joint.clone(),
                    });
                }
                if b.bus == a.bus && b.actuator.can_id() == a.actuator.can_id() {
                    return Err(RobotConfigError::DuplicateCanId {
                        bus: self.buses[a.bus].name.clone(),
                        can_id: a.actuator.can_id(),
                        first: b.joint.clone(),
                        second: a.joint.clone(),
                    });
                }
            }
        }
        for (name, q) in &self.start_positions_rad {
            finite(format!("start position of `{name}`"), *q, false)?;
        }
        Ok(())
    }
}
