//! Robot files for the URDFs of the public corpus (example-robot-data 6.0.0 from PyPI), so a
//! test or a bench can run a published robot through the whole stack: robot file, RobStride
//! firmware on every joint, CAN buses, the articulated physics on the ground.
//!
//! The corpus is not in the repository: `pip install example-robot-data==6.0.0` and point
//! [`CORPUS_ENV`] at its `…/cmeel.prefix/share/example-robot-data`; [`corpus_root`] reads it
//! (a test without it prints one `skipped:` line, or fails under `ARMHIL_REQUIRE_TOOLS=1`).
//!
//! [`plan`] reads a URDF and chooses, deterministically:
//!
//! - an actuator for every revolute or continuous joint that is not a `<mimic>` follower: the
//!   RobStride model (RS00 … RS06) of smallest peak torque at or above the joint's URDF effort
//!   (of two with the same peak, the faster), the strongest (RS04, 120 N·m) when none is;
//! - at most four buses, one per kinematic subtree: the tree is cut where it branches, the
//!   largest part first, while there are buses left (a quadruped's four legs; a humanoid's two
//!   legs, its waist with one arm, the other arm); ids 1, 2, … on each bus in URDF order;
//! - a floating base whose root starts so high that the lowest collision point of the start
//!   pose is [`RobotFileOptions::clearance_m`] above the ground (feet just touching);
//! - the start pose: the given angles, every other joint at 0, clamped to the joint's limits.
//!
//! [`robot_file_for`] writes it as a robot file (grammar: `robots/README.md`). [`LEGGED`]
//! lists the corpus's legged robots with a standing pose and the operation-control gains,
//! per N·m of joint torque, that hold them up (found by `tests/integration/corpus_robots.rs`).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use sim::description::{CollisionGeometry, Description, MissingMeshes, PackagePaths};
use sim::physics::articulated::ArticulatedWorld;
use sim::physics::{JointKind, WorldConfig};
use sim::robstride::{Model, RangeTable};

/// The variable naming the corpus folder (`…/cmeel.prefix/share/example-robot-data`).
pub const CORPUS_ENV: &str = "ARMHIL_URDF_CORPUS";

/// The ROS package name the corpus's URDFs use in their `package://` URIs.
pub const PACKAGE: &str = "example-robot-data";

/// Most buses a generated robot has (`can0` … `can3`).
pub const MAX_BUSES: usize = 4;

/// The corpus folder from [`CORPUS_ENV`], or `None` after one line `skipped: <test>:
/// ARMHIL_URDF_CORPUS not set — …` on stderr. Under `ARMHIL_REQUIRE_TOOLS=1` an unset variable
/// panics (CI must not skip); a set one that is not the corpus always panics.
pub fn corpus_root(test: &str) -> Option<PathBuf> {
    match std::env::var_os(CORPUS_ENV).filter(|v| !v.is_empty()) {
        Some(root) => {
            let root = PathBuf::from(root);
            assert!(
                root.join("robots").is_dir(),
                "{CORPUS_ENV}={} has no `robots` folder: point it at \
                 …/cmeel.prefix/share/example-robot-data",
                root.display()
            );
            Some(root)
        }
        None => {
            let reason = format!(
                "{test}: {CORPUS_ENV} not set — pip install example-robot-data==6.0.0 and \
                 point it at …/cmeel.prefix/share/example-robot-data"
            );
            if crate::tools::tools_required() {
                panic!(
                    "{reason} ({} is set, so a missing corpus is a failure)",
                    crate::tools::REQUIRE_TOOLS_ENV
                );
            }
            // Straight to the process's stderr: libtest captures a passing test's output.
            let _ = writeln!(std::io::stderr(), "skipped: {reason}");
            None
        }
    }
}

/// What [`plan`] may not guess.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotFileOptions {
    /// The `robot:` name; `None`: the URDF file's stem.
    pub name: Option<String>,
    /// Start angles (rad) by joint name; every other actuated joint starts at 0. Each is
    /// clamped to its joint's limits.
    pub start_rad: Vec<(String, f64)>,
    /// Height of the start pose's lowest collision point above the ground (m).
    pub clearance_m: f64,
    /// The robot file's `gantry:` (`off`, `until_enabled`, `until_released`).
    pub gantry: String,
    /// Most buses (1 to [`MAX_BUSES`]).
    pub max_buses: usize,
}

impl Default for RobotFileOptions {
    fn default() -> Self {
        Self {
            name: None,
            start_rad: Vec::new(),
            clearance_m: 0.001,
            gantry: "until_enabled".to_owned(),
            max_buses: MAX_BUSES,
        }
    }
}

/// One actuated joint of a [`CorpusRobot`].
#[derive(Debug, Clone, PartialEq)]
pub struct CorpusActuator {
    /// The URDF joint.
    pub joint: String,
    /// The joint's URDF `effort` (N·m; may be 0 or absurd, as published).
    pub effort_nm: f64,
    /// The actuator chosen for it.
    pub model: Model,
    /// Its bus (index into [`CorpusRobot::buses`]).
    pub bus: usize,
    /// Its CAN id on that bus.
    pub id: u8,
    /// The joint's start angle (rad), within its limits.
    pub start_rad: f64,
    /// The joint's limits (rad; infinite for a continuous joint).
    pub limits_rad: (f64, f64),
}

impl CorpusActuator {
    /// The torque (N·m) the joint can get: its URDF effort, at most the actuator's peak (the
    /// whole peak when the URDF gives no effort).
    pub fn torque_nm(&self) -> f64 {
        let peak = self.model.spec().peak_torque_nm;
        if self.effort_nm.is_finite() && self.effort_nm > 0.0 {
            self.effort_nm.min(peak)
        } else {
            peak
        }
    }

    /// Operation-control gains `kp = kp_per_nm · τ`, `kd = kd_per_nm · τ` with τ =
    /// [`CorpusActuator::torque_nm`], each within what the model's command can carry.
    pub fn gains(&self, kp_per_nm: f64, kd_per_nm: f64) -> (f64, f64) {
        let ranges = self.model.ranges(RangeTable::Manual);
        let torque = self.torque_nm();
        (
            (kp_per_nm * torque).clamp(0.0, f64::from(ranges.kp_max)),
            (kd_per_nm * torque).clamp(0.0, f64::from(ranges.kd_max)),
        )
    }
}

/// A corpus URDF as a robot: what [`robot_file_for`] writes.
#[derive(Debug, Clone, PartialEq)]
pub struct CorpusRobot {
    /// The `robot:` name.
    pub name: String,
    /// The URDF (absolute, so the robot file may be written anywhere).
    pub urdf: PathBuf,
    /// The folder `package://example-robot-data/` names (absolute).
    pub package_root: PathBuf,
    /// The URDF's root link.
    pub root_link: String,
    /// Total mass of the links (kg).
    pub mass_kg: f64,
    /// The root link's start height above the ground (m).
    pub start_height_m: f64,
    /// The link with the start pose's lowest collision point.
    pub lowest_link: String,
    /// The `gantry:` word.
    pub gantry: String,
    /// Bus names (`can0` …).
    pub buses: Vec<String>,
    /// The actuators, in URDF joint order.
    pub actuators: Vec<CorpusActuator>,
}

impl CorpusRobot {
    /// The actuator of joint `joint`.
    pub fn actuator(&self, joint: &str) -> Option<&CorpusActuator> {
        self.actuators.iter().find(|a| a.joint == joint)
    }

    /// The robot file (YAML, `robots/README.md`'s grammar; paths absolute, so it may be
    /// written anywhere).
    pub fn to_yaml(&self) -> String {
        let mut out = String::new();
        let w = &mut out;
        let _ = writeln!(
            w,
            "# Written by testkit::corpus from a URDF of example-robot-data 6.0.0: every\n\
             # revolute joint that is not a <mimic> follower driven by the smallest RobStride\n\
             # whose peak torque covers the joint's URDF effort, one bus per kinematic subtree."
        );
        let _ = writeln!(w, "robot: {}", quoted(&self.name));
        let _ = writeln!(w, "urdf: {}", quoted(&self.urdf.to_string_lossy()));
        let _ = writeln!(
            w,
            "packages: {{{}: {}}}",
            quoted(PACKAGE),
            quoted(&self.package_root.to_string_lossy())
        );
        let _ = writeln!(w, "missing_meshes: refuse");
        let _ = writeln!(w, "base: floating");
        let _ = writeln!(
            w,
            "# The lowest collision point (link `{}`) just above the ground; {:.1} kg.",
            self.lowest_link, self.mass_kg
        );
        let _ = writeln!(w, "start_height_m: {}", number(self.start_height_m));
        let _ = writeln!(w, "gantry: {}", self.gantry);
        let _ = writeln!(w, "buses:");
        for bus in &self.buses {
            let _ = writeln!(w, "  - {{name: {bus}, bitrate: 1000000}}");
        }
        let _ = writeln!(w, "actuators:");
        for a in &self.actuators {
            let _ = writeln!(
                w,
                "  - {{joint: {}, model: {}, id: {}, bus: {}}}   # effort {} N·m",
                quoted(&a.joint),
                a.model.name(),
                a.id,
                self.buses[a.bus],
                a.effort_nm
            );
        }
        let _ = writeln!(w, "start_rad:");
        for a in &self.actuators {
            let _ = writeln!(
                w,
                "  - {{joint: {}, rad: {}}}",
                quoted(&a.joint),
                number(a.start_rad)
            );
        }
        out
    }
}

/// The robot file of the corpus URDF `urdf_path` (its `package://example-robot-data/` names
/// resolved in `corpus_root`); see [`plan`]. Panics with the reason when the URDF does not
/// load (test support: the caller has nothing better to do with it).
pub fn robot_file_for(urdf_path: &Path, corpus_root: &Path, options: &RobotFileOptions) -> String {
    plan(urdf_path, corpus_root, options)
        .unwrap_or_else(|e| panic!("{}: {e}", urdf_path.display()))
        .to_yaml()
}

/// Reads the URDF `urdf_path` and chooses actuators, buses, start pose and start height (see
/// the module's documentation).
pub fn plan(
    urdf_path: &Path,
    corpus_root: &Path,
    options: &RobotFileOptions,
) -> Result<CorpusRobot, String> {
    if !(1..=MAX_BUSES).contains(&options.max_buses) {
        return Err(format!(
            "max_buses must be 1..={MAX_BUSES}, got {}",
            options.max_buses
        ));
    }
    let text = std::fs::read_to_string(urdf_path).map_err(|e| format!("cannot read: {e}"))?;
    let paths = PackagePaths {
        urdf_dir: urdf_path.parent().map(Path::to_owned),
        packages: vec![(PACKAGE.to_owned(), corpus_root.to_owned())],
        ros_package_path: Vec::new(),
        ament_prefix_path: Vec::new(),
    };
    let description = Description::parse(text, paths).map_err(|e| e.to_string())?;
    let geometry = description
        .collision_geometry(MissingMeshes::Refuse)
        .map_err(|e| e.to_string())?;
    let config = WorldConfig {
        floating_base_height_m: Some(0.0),
        ..WorldConfig::default()
    };
    let mut world = ArticulatedWorld::from_description(&description, &geometry, config)
        .map_err(|e| e.to_string())?;
    for (joint, _) in &options.start_rad {
        if world.joint_index(joint).is_none() {
            return Err(format!("a start angle for `{joint}`, not a movable joint"));
        }
    }

    // The actuated joints (world order = URDF order) and their start angles.
    let joints = world.joints().to_vec();
    let mut q = vec![0.0; joints.len()];
    for (i, info) in joints.iter().enumerate() {
        let given = options
            .start_rad
            .iter()
            .find(|(j, _)| *j == info.name)
            .map_or(0.0, |(_, v)| *v);
        q[i] = given.clamp(info.lower, info.upper);
    }
    let actuated: Vec<usize> = (0..joints.len())
        .filter(|&i| joints[i].kind == JointKind::Revolute && joints[i].mimic.is_none())
        .collect();
    if actuated.is_empty() {
        return Err("no revolute joint to put an actuator on".to_owned());
    }

    // Start height: the start pose with the root at the origin, lifted to the clearance.
    world.set_joint_positions(&q).map_err(|e| e.to_string())?;
    let (low_link, low_z) =
        lowest_point(&geometry, &world).ok_or("no collision shape: nothing to stand on")?;
    let model = world.model();
    let links = model.link_names();
    let start_height_m = options.clearance_m - low_z;

    let groups = split_into_buses(
        &description,
        model.root_link_name(),
        &joints,
        &actuated,
        options.max_buses,
    );
    let mut actuators = Vec::new();
    for &i in &actuated {
        let info = &joints[i];
        let bus = groups
            .iter()
            .position(|g| g.contains(&i))
            .expect("every actuated joint is on a bus");
        let id = groups[bus].iter().filter(|&&j| j < i).count() + 1;
        actuators.push(CorpusActuator {
            joint: info.name.clone(),
            effort_nm: info.effort_limit,
            model: model_for(info.effort_limit),
            bus,
            id: u8::try_from(id)
                .ok()
                .filter(|id| *id <= 127)
                .ok_or_else(|| format!("more than 127 actuators on bus can{bus}"))?,
            start_rad: q[i],
            limits_rad: (info.lower, info.upper),
        });
    }
    let name = options.name.clone().unwrap_or_else(|| {
        urdf_path
            .file_stem()
            .map_or_else(|| "robot".to_owned(), |s| s.to_string_lossy().into_owned())
    });
    let absolute = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
    Ok(CorpusRobot {
        name,
        urdf: absolute(urdf_path),
        package_root: absolute(corpus_root),
        root_link: model.root_link_name().to_owned(),
        mass_kg: model.inertials().iter().map(|l| l.mass_kg).sum(),
        start_height_m,
        lowest_link: links[low_link].clone(),
        gantry: options.gantry.clone(),
        buses: (0..groups.len()).map(|k| format!("can{k}")).collect(),
        actuators,
    })
}

/// The RobStride models a joint may get: RS00 … RS06 (EL05 is a teaching model).
const MODELS: [Model; 7] = [
    Model::RS00,
    Model::RS01,
    Model::RS02,
    Model::RS03,
    Model::RS04,
    Model::RS05,
    Model::RS06,
];

/// The model of smallest peak torque at or above `effort_nm` (of equal peaks the one of higher
/// no-load speed: RS02 rather than RS01), or the strongest when none reaches it.
pub fn model_for(effort_nm: f64) -> Model {
    let mut models = MODELS;
    models.sort_by(|a, b| {
        let (a, b) = (a.spec(), b.spec());
        a.peak_torque_nm
            .total_cmp(&b.peak_torque_nm)
            .then(b.no_load_speed_rad_s.total_cmp(&a.no_load_speed_rad_s))
    });
    let effort = if effort_nm.is_finite() {
        effort_nm
    } else {
        f64::INFINITY
    };
    models
        .iter()
        .copied()
        .find(|m| m.spec().peak_torque_nm >= effort)
        .unwrap_or(models[models.len() - 1])
}

/// The lowest collision point of `world` as it stands: its link and height (m).
fn lowest_point(geometry: &CollisionGeometry, world: &ArticulatedWorld) -> Option<(usize, f64)> {
    geometry.lowest_point(&world.link_poses())
}

/// A part of the robot on one bus: its actuated joints (world indices) and, when it can be cut
/// further, the joints above its branching point and the edges (URDF joints) below it.
struct Part {
    members: Vec<usize>,
    cut: Option<(Vec<usize>, Vec<usize>)>,
}

/// The URDF tree as edges (URDF joints) below each link, with the actuated joint each edge
/// is (world index), if any.
struct Tree<'a> {
    /// Per URDF joint: parent link, child link, world index when actuated.
    edges: Vec<(&'a str, &'a str, Option<usize>)>,
    /// Per link: its child edges, in URDF order.
    below: BTreeMap<&'a str, Vec<usize>>,
}

impl<'a> Tree<'a> {
    fn new(description: &'a Description, actuated: &[(usize, &str)]) -> Self {
        let mut edges = Vec::new();
        let mut below: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (e, joint) in description.robot().joints.iter().enumerate() {
            let index = actuated
                .iter()
                .find(|(_, name)| *name == joint.name)
                .map(|(i, _)| *i);
            edges.push((joint.parent.link.as_str(), joint.child.link.as_str(), index));
            below.entry(joint.parent.link.as_str()).or_default().push(e);
        }
        Self { edges, below }
    }

    /// The actuated joints of edge `e` and everything below it.
    fn members(&self, e: usize) -> Vec<usize> {
        let mut out: Vec<usize> = self.edges[e].2.into_iter().collect();
        for &child in self.below.get(self.edges[e].1).into_iter().flatten() {
            out.extend(self.members(child));
        }
        out
    }

    /// From `link` down while the tree does not branch (one child edge with actuated joints):
    /// the actuated joints passed, and the edges where it branches (none at a leaf).
    fn descend(&self, mut link: &'a str) -> (Vec<usize>, Vec<usize>) {
        let mut chain = Vec::new();
        loop {
            let live: Vec<usize> = self
                .below
                .get(link)
                .into_iter()
                .flatten()
                .copied()
                .filter(|&e| !self.members(e).is_empty())
                .collect();
            if live.len() != 1 {
                return (chain, live);
            }
            let e = live[0];
            chain.extend(self.edges[e].2);
            link = self.edges[e].1;
        }
    }

    /// The part made of the joints `prefix` and the subtrees of `edges`.
    fn part(&self, prefix: Vec<usize>, edges: &[usize]) -> Part {
        let mut members = prefix.clone();
        for &e in edges {
            members.extend(self.members(e));
        }
        let cut = match edges {
            [e] => {
                let mut chain = prefix;
                chain.extend(self.edges[*e].2);
                let (more, children) = self.descend(self.edges[*e].1);
                chain.extend(more);
                (children.len() >= 2).then_some((chain, children))
            }
            _ => None,
        };
        Part { members, cut }
    }
}

/// The actuated joints `actuated` (world indices into `joints`) in at most `max_buses` groups,
/// one per kinematic subtree: the robot is cut where its tree branches, the part with the most
/// actuators first, while buses are left; when a branching point has more branches than buses
/// left, the branches are shared out largest first to the least loaded bus (the joints above
/// the branching point count on the first). Groups sorted by their first joint.
fn split_into_buses(
    description: &Description,
    root_link: &str,
    joints: &[sim::physics::JointInfo],
    actuated: &[usize],
    max_buses: usize,
) -> Vec<Vec<usize>> {
    let named: Vec<(usize, &str)> = actuated
        .iter()
        .map(|&i| (i, joints[i].name.as_str()))
        .collect();
    let tree = Tree::new(description, &named);
    let (chain, children) = tree.descend(root_link);
    let mut parts = vec![Part {
        members: actuated.to_vec(),
        cut: (children.len() >= 2).then_some((chain, children)),
    }];
    while parts.len() < max_buses {
        let Some(largest) = parts
            .iter()
            .enumerate()
            .filter(|(_, p)| p.cut.is_some())
            .max_by(|(a, pa), (b, pb)| pa.members.len().cmp(&pb.members.len()).then(b.cmp(a)))
            .map(|(k, _)| k)
        else {
            break;
        };
        let part = parts.remove(largest);
        let (chain, mut children) = part.cut.expect("a part that can be cut");
        let slots = children.len().min(max_buses - parts.len());
        children.sort_by_key(|&e| std::cmp::Reverse(tree.members(e).len()));
        let mut bins: Vec<(usize, Vec<usize>, Vec<usize>)> = (0..slots)
            .map(|k| {
                let prefix = if k == 0 { chain.clone() } else { Vec::new() };
                (prefix.len(), prefix, Vec::new())
            })
            .collect();
        for e in children {
            let bin = (0..slots)
                .min_by_key(|&k| (bins[k].0, k))
                .expect("at least one slot");
            bins[bin].0 += tree.members(e).len();
            bins[bin].2.push(e);
        }
        for (load, prefix, mut edges) in bins {
            if load == 0 {
                continue;
            }
            edges.sort_unstable();
            parts.insert(largest, tree.part(prefix, &edges));
        }
    }
    let mut groups: Vec<Vec<usize>> = parts
        .into_iter()
        .map(|mut p| {
            p.members.sort_unstable();
            p.members
        })
        .filter(|m| !m.is_empty())
        .collect();
    groups.sort();
    groups
}

/// A legged robot of the corpus with what it needs to stand: a standing pose and the
/// operation-control gains per N·m of joint torque ([`CorpusActuator::gains`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeggedRobot {
    /// The URDF, relative to the corpus folder.
    pub urdf: &'static str,
    /// Start angles (rad) of the joints not at 0: the robot's published standing pose.
    pub stance: &'static [(&'static str, f64)],
    /// Stiffness per N·m of joint torque (N·m/rad per N·m).
    pub kp_per_nm: f64,
    /// Damping per N·m of joint torque (N·m·s/rad per N·m).
    pub kd_per_nm: f64,
}

impl LeggedRobot {
    /// The robot's name: its URDF file's stem (`go1`).
    pub fn name(&self) -> &'static str {
        let file = self.urdf.rsplit('/').next().unwrap_or(self.urdf);
        file.strip_suffix(".urdf").unwrap_or(file)
    }

    /// [`RobotFileOptions`] starting it in its standing pose on a gantry.
    pub fn options(&self) -> RobotFileOptions {
        RobotFileOptions {
            name: Some(self.name().to_owned()),
            start_rad: self
                .stance
                .iter()
                .map(|(j, v)| ((*j).to_owned(), *v))
                .collect(),
            ..RobotFileOptions::default()
        }
    }

    /// Its plan in the corpus at `corpus_root`.
    pub fn plan(&self, corpus_root: &Path) -> Result<CorpusRobot, String> {
        plan(&corpus_root.join(self.urdf), corpus_root, &self.options())
    }
}

/// The four legs of a Unitree quadruped at hip 0, thigh `thigh`, calf `calf`.
macro_rules! unitree_legs {
    ($thigh:expr, $calf:expr) => {
        &[
            ("FL_thigh_joint", $thigh),
            ("FL_calf_joint", $calf),
            ("FR_thigh_joint", $thigh),
            ("FR_calf_joint", $calf),
            ("RL_thigh_joint", $thigh),
            ("RL_calf_joint", $calf),
            ("RR_thigh_joint", $thigh),
            ("RR_calf_joint", $calf),
        ]
    };
}

/// The legged robots of the corpus. Standing poses: the `standing` (`half_sitting` for
/// Talos) states of the corpus's own SRDF files; the G1 (no SRDF) with its knees bent 0.3 rad
/// and its feet flat (hip + knee + ankle pitch = 0). Gains: every robot stands 8 s with any
/// kp from 12 to 60 and kd from 0.02 to 0.1 per N·m (`tests/integration/corpus_robots.rs`);
/// the same value from the middle is taken for all.
pub const LEGGED: &[LeggedRobot] = &[
    LeggedRobot {
        urdf: "robots/go1_description/urdf/go1.urdf",
        stance: unitree_legs!(0.8, -1.853),
        kp_per_nm: 20.0,
        kd_per_nm: 0.05,
    },
    LeggedRobot {
        urdf: "robots/a1_description/urdf/a1.urdf",
        stance: unitree_legs!(0.8, -1.81),
        kp_per_nm: 20.0,
        kd_per_nm: 0.05,
    },
    LeggedRobot {
        urdf: "robots/anymal_b_simple_description/robots/anymal.urdf",
        stance: &[
            ("LF_HAA", -0.1),
            ("LF_HFE", 0.7),
            ("LF_KFE", -1.0),
            ("RF_HAA", 0.1),
            ("RF_HFE", 0.7),
            ("RF_KFE", -1.0),
            ("LH_HAA", -0.1),
            ("LH_HFE", -0.7),
            ("LH_KFE", 1.0),
            ("RH_HAA", 0.1),
            ("RH_HFE", -0.7),
            ("RH_KFE", 1.0),
        ],
        kp_per_nm: 20.0,
        kd_per_nm: 0.05,
    },
    LeggedRobot {
        urdf: "robots/solo_description/robots/solo12.urdf",
        stance: &[
            ("FL_HAA", 0.1),
            ("FL_HFE", 0.8),
            ("FL_KFE", -1.6),
            ("FR_HAA", -0.1),
            ("FR_HFE", 0.8),
            ("FR_KFE", -1.6),
            ("HL_HAA", 0.1),
            ("HL_HFE", -0.8),
            ("HL_KFE", 1.6),
            ("HR_HAA", -0.1),
            ("HR_HFE", -0.8),
            ("HR_KFE", 1.6),
        ],
        kp_per_nm: 20.0,
        kd_per_nm: 0.05,
    },
    LeggedRobot {
        urdf: "robots/g1_description/urdf/g1_29dof_rev_1_0.urdf",
        stance: &[
            ("left_hip_pitch_joint", -0.1),
            ("left_knee_joint", 0.3),
            ("left_ankle_pitch_joint", -0.2),
            ("right_hip_pitch_joint", -0.1),
            ("right_knee_joint", 0.3),
            ("right_ankle_pitch_joint", -0.2),
        ],
        kp_per_nm: 20.0,
        kd_per_nm: 0.05,
    },
    LeggedRobot {
        urdf: "robots/talos_data/robots/talos_reduced.urdf",
        stance: &[
            ("arm_left_1_joint", 0.25847),
            ("arm_left_2_joint", 0.173046),
            ("arm_left_3_joint", -0.0002),
            ("arm_left_4_joint", -0.525366),
            ("arm_left_7_joint", 0.1),
            ("arm_right_1_joint", -0.25847),
            ("arm_right_2_joint", -0.173046),
            ("arm_right_3_joint", 0.0002),
            ("arm_right_4_joint", -0.525366),
            ("arm_right_7_joint", 0.1),
            ("leg_left_3_joint", -0.411354),
            ("leg_left_4_joint", 0.859395),
            ("leg_left_5_joint", -0.448041),
            ("leg_left_6_joint", -0.001708),
            ("leg_right_3_joint", -0.411354),
            ("leg_right_4_joint", 0.859395),
            ("leg_right_5_joint", -0.448041),
            ("leg_right_6_joint", -0.001708),
            ("torso_2_joint", 0.006761),
        ],
        kp_per_nm: 20.0,
        kd_per_nm: 0.05,
    },
];

/// `text` as a YAML double-quoted scalar.
fn quoted(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04x}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A float YAML reads back as the same float (always with a decimal point).
fn number(value: f64) -> String {
    let text = format!("{value}");
    if text.contains(['.', 'e', 'E', 'n', 'N']) {
        text
    } else {
        format!("{text}.0")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smallest_model_that_covers_the_effort_is_chosen() {
        assert_eq!(model_for(0.0), Model::RS05);
        assert_eq!(model_for(5.5), Model::RS05);
        assert_eq!(model_for(5.6), Model::RS00);
        assert_eq!(model_for(16.0), Model::RS02);
        assert_eq!(model_for(23.7), Model::RS06);
        assert_eq!(model_for(40.0), Model::RS03);
        assert_eq!(model_for(80.0), Model::RS04);
        assert_eq!(model_for(1000.0), Model::RS04);
        assert_eq!(model_for(f64::NAN), Model::RS04);
    }

    #[test]
    fn yaml_scalars_read_back() {
        assert_eq!(quoted(r#"a "b" \c"#), r#""a \"b\" \\c""#);
        assert_eq!(number(0.0), "0.0");
        assert_eq!(number(-0.0), "-0.0");
        assert_eq!(number(0.25), "0.25");
        assert_eq!(number(3.0), "3.0");
    }

    #[test]
    fn legged_robots_are_named_by_their_urdf() {
        let names: Vec<&str> = LEGGED.iter().map(LeggedRobot::name).collect();
        assert_eq!(
            names,
            [
                "go1",
                "a1",
                "anymal",
                "solo12",
                "g1_29dof_rev_1_0",
                "talos_reduced"
            ]
        );
    }
}
