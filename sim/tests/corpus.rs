//! The published robots of example-robot-data 6.0.0 (PyPI), every `*.urdf` of it, through
//! the whole loading path: URDF checks and parsing, `package://` names resolved the way ROS
//! resolves them, collision meshes read and hulled (a missing mesh refused), the
//! articulated-body world built and stepped.
//!
//! The corpus is not in the repository: `pip install example-robot-data==6.0.0` and point
//! `ARMHIL_URDF_CORPUS` at its `…/cmeel.prefix/share/example-robot-data`. Unset, the tests
//! print one `skipped:` line and pass, unless `ARMHIL_REQUIRE_TOOLS=1` (CI), where they fail.
//!
//! - every file loads, except the few in [`EXPECTED_FAILURES`] (each with the error it must
//!   give), and its fixed-base world stays finite for 200 ms with no torque;
//! - the legged robots ([`LEGGED`]), free, dropped from 2 cm with their joints unpowered,
//!   come to rest on the ground plane without anything sinking through it.

use std::io::Write;
use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use sim::description::{CollisionGeometry, Description, MissingMeshes, PackagePaths};
use sim::physics::articulated::ArticulatedWorld;
use sim::physics::WorldConfig;

/// Where loading a file stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    /// Reading the file.
    Read,
    /// `Description::parse`.
    Parse,
    /// `Description::collision_geometry` (meshes refused when missing).
    Geometry,
    /// `ArticulatedWorld::from_description`.
    World,
    /// Stepping the fixed-base world ([`FIXED_STEPS`] steps, no torque).
    Step,
}

/// The files that do not load or do not run, where they stop, a piece of the error they must
/// give, and why. Everything else in the corpus must load and run; a file listed here that
/// does fails the test too (the table would be stale: take it off).
///
/// Two kinds: files the corpus publishes broken (refused on purpose), and limits of armhil or
/// of the libraries it reads with (marked "armhil:"), to be lifted.
const EXPECTED_FAILURES: &[(&str, Stage, &str, &str)] = &[
    (
        "robots/alex_description/urdf/alex_psyonic_hands.urdf",
        Stage::World,
        "its <mimic> leader `index_q1` is not a movable joint of the URDF",
        "the left hand's finger joints mimic `index_q1` …, which do not exist (the joints are \
         `Left_index_q1` …)",
    ),
    (
        "robots/romeo_description/urdf/romeo.urdf",
        Stage::World,
        "joint LHand moves nothing with mass or inertia",
        "its hands' joints (LHand, RHand) move links with no mass and no inertia, and the \
         fingers that mimic them have none either: nothing for a motor to accelerate",
    ),
    (
        "robots/romeo_description/urdf/romeo_laas_small.urdf",
        Stage::Parse,
        "link `body`'s inertia is not positive semi-definite",
        "its `body` inertia has |ixz| 0.0575 beside izz 0.0212: no body has it",
    ),
    (
        "robots/ur_description/urdf/ur3.urdf",
        Stage::World,
        "do not form a single tree (roots: [])",
        "an empty `<robot>` (its xacro expanded to nothing): no links",
    ),
];

/// The legged robots dropped on the ground (those of the corpus that have legs and stand).
const LEGGED: &[&str] = &[
    "robots/a1_description/urdf/a1.urdf",
    "robots/anymal_b_simple_description/robots/anymal.urdf",
    "robots/anymal_c_simple_description/urdf/anymal.urdf",
    "robots/g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "robots/go1_description/urdf/go1.urdf",
    "robots/solo_description/robots/solo12.urdf",
    "robots/talos_data/robots/talos_reduced.urdf",
];

/// Steps (1 ms) of the fixed-base run of every file.
const FIXED_STEPS: usize = 200;
/// Steps (1 ms) of the legged robots' unpowered fall.
const LEGGED_STEPS: usize = 3000;
/// Height of the lowest collision point above the ground when a legged robot is let go (m).
const DROP_HEIGHT_M: f64 = 0.02;
/// How far below the ground any collision point may be at the end (m).
const MAX_SINK_M: f64 = 0.02;

/// The corpus folder, or `None` after one `skipped:` line (see [`testkit::corpus::corpus_root`]).
fn corpus_root() -> Option<PathBuf> {
    testkit::corpus::corpus_root("urdf_corpus")
}

/// Every `*.urdf` below `root`, relative to it, sorted.
fn urdf_files(root: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut folders = vec![root.to_owned()];
    while let Some(folder) = folders.pop() {
        let entries = std::fs::read_dir(&folder)
            .unwrap_or_else(|e| panic!("cannot list {}: {e}", folder.display()));
        for entry in entries {
            let entry = entry.unwrap_or_else(|e| panic!("cannot list {}: {e}", folder.display()));
            let path = entry.path();
            let kind = entry.file_type().expect("file type");
            if kind.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "urdf") {
                found.push(path.strip_prefix(root).expect("below root").to_owned());
            }
        }
    }
    found.sort();
    found
}

/// Where the corpus's URDFs find their meshes: `package://example-robot-data/…` through the
/// ament prefix two folders above the corpus (`cmeel.prefix`), b1's own package name mapped
/// to its folder; nothing from the environment, so the result does not depend on it.
fn package_paths(root: &Path, file: &Path) -> PackagePaths {
    let prefix = root
        .parent()
        .and_then(Path::parent)
        .expect("the corpus folder is …/share/example-robot-data");
    PackagePaths {
        urdf_dir: file.parent().map(Path::to_owned),
        packages: vec![(
            "b1_description".to_owned(),
            root.join("robots/b1_description"),
        )],
        ros_package_path: Vec::new(),
        ament_prefix_path: vec![prefix.to_owned()],
    }
}

/// A file loaded as far as its collision geometry.
struct Loaded {
    description: Description,
    geometry: CollisionGeometry,
}

/// Reads, parses and hulls `file` (relative to `root`); the stage that failed and its error.
fn load(root: &Path, file: &Path) -> Result<Loaded, (Stage, String)> {
    let path = root.join(file);
    let text = std::fs::read_to_string(&path).map_err(|e| (Stage::Read, e.to_string()))?;
    let description = Description::parse(text, package_paths(root, &path))
        .map_err(|e| (Stage::Parse, e.to_string()))?;
    let geometry = description
        .collision_geometry(MissingMeshes::Refuse)
        .map_err(|e| (Stage::Geometry, e.to_string()))?;
    Ok(Loaded {
        description,
        geometry,
    })
}

/// The world of a loaded file: fixed base (`None`) or free, its root `height` above the ground.
fn world(loaded: &Loaded, height: Option<f64>) -> Result<ArticulatedWorld, (Stage, String)> {
    let config = WorldConfig {
        floating_base_height_m: height,
        ..WorldConfig::default()
    };
    ArticulatedWorld::from_description(&loaded.description, &loaded.geometry, config)
        .map_err(|e| (Stage::World, e.to_string()))
}

/// Builds the fixed-base world of a loaded file and steps it [`FIXED_STEPS`] ms from joints at
/// 0 (clamped to their limits) with no torque; it must stay finite.
fn run_fixed(loaded: &Loaded) -> Result<(), (Stage, String)> {
    let mut world = world(loaded, None)?;
    let zero = vec![0.0; world.joints().len()];
    world
        .set_joint_positions(&zero)
        .map_err(|e| (Stage::World, e.to_string()))?;
    for _ in 0..FIXED_STEPS {
        world.step(&zero);
    }
    world
        .check_finite()
        .map_err(|e| (Stage::Step, e.to_string()))
}

/// The lowest point (z, m) of every collision shape at the link poses `poses`: a box's
/// lowest corner, a cylinder's lowest rim point, a sphere's or a capsule's bottom, a hull's
/// lowest contact point.
fn lowest_points(geometry: &CollisionGeometry, poses: &[Isometry3<f64>]) -> Vec<(usize, f64)> {
    geometry.lowest_points(poses)
}

/// The lowest of `points` and its link's name.
fn lowest<'a>(points: &[(usize, f64)], links: &'a [String]) -> Option<(&'a str, f64)> {
    points
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(link, z)| (links[*link].as_str(), *z))
}

/// Every file loads (or fails as [`EXPECTED_FAILURES`] says) and its fixed-base world stays
/// finite for [`FIXED_STEPS`] ms with no torque.
#[test]
fn every_urdf_loads_and_a_fixed_base_world_stays_finite_unpowered() {
    let Some(root) = corpus_root() else {
        return;
    };
    let files = urdf_files(&root);
    assert!(!files.is_empty(), "no *.urdf below {}", root.display());
    let mut problems = Vec::new();
    for (listed, ..) in EXPECTED_FAILURES {
        if !files.iter().any(|f| f == Path::new(listed)) {
            problems.push(format!("{listed}: listed as failing but not in the corpus"));
        }
    }
    let mut loaded_count = 0;
    for file in &files {
        let name = file.display().to_string();
        let expected = EXPECTED_FAILURES.iter().find(|(f, ..)| *f == name);
        let outcome = load(&root, file).and_then(|loaded| run_fixed(&loaded));
        match (outcome, expected) {
            (Ok(()), None) => loaded_count += 1,
            (Ok(()), Some((_, stage, ..))) => problems.push(format!(
                "{name}: loads and runs, but is listed as failing at {stage:?}: take it off \
                 the list"
            )),
            (Err((stage, error)), None) => {
                problems.push(format!("{name}: fails at {stage:?}: {error}"));
            }
            (Err((stage, error)), Some((_, want_stage, want, why))) => {
                if stage == *want_stage && error.contains(want) {
                    let _ = writeln!(
                        std::io::stderr(),
                        "urdf_corpus: {name}: fails at {stage:?} as expected: {why}"
                    );
                } else {
                    problems.push(format!(
                        "{name}: expected to fail at {want_stage:?} with `{want}`, \
                         failed at {stage:?}: {error}"
                    ));
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{} of {} files:\n{}",
        problems.len(),
        files.len(),
        problems.join("\n")
    );
    let _ = writeln!(
        std::io::stderr(),
        "urdf_corpus: {loaded_count} of {} files load and stay finite for {FIXED_STEPS} ms \
         with a fixed base ({} expected failures)",
        files.len(),
        EXPECTED_FAILURES.len()
    );
}

/// Each of [`LEGGED`] that loads, dropped unpowered, rests on the ground: its root above it,
/// no collision point more than [`MAX_SINK_M`] below it.
#[test]
fn legged_robots_dropped_unpowered_come_to_rest_on_the_ground() {
    let Some(root) = corpus_root() else {
        return;
    };
    let mut problems = Vec::new();
    let mut tried = 0;
    for file in LEGGED {
        let path = Path::new(file);
        if !root.join(path).is_file() {
            problems.push(format!("{file}: not in the corpus"));
            continue;
        }
        if let Some((_, stage, _, why)) = EXPECTED_FAILURES.iter().find(|(f, ..)| f == file) {
            let _ = writeln!(
                std::io::stderr(),
                "urdf_corpus legged: {file}: not dropped, it fails at {stage:?}: {why}"
            );
            continue;
        }
        tried += 1;
        match drop_on_the_ground(&root, path) {
            Ok(line) => {
                let _ = writeln!(std::io::stderr(), "urdf_corpus legged: {line}");
            }
            Err(problem) => problems.push(format!("{file}: {problem}")),
        }
    }
    assert!(
        problems.is_empty(),
        "{} of {tried} legged robots:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// Drops the robot of `file`: joints at 0 (clamped to their limits), its lowest collision
/// point [`DROP_HEIGHT_M`] above the ground, no torque, [`LEGGED_STEPS`] ms. The line to
/// print, or what went wrong.
fn drop_on_the_ground(root: &Path, file: &Path) -> Result<String, String> {
    let loaded = load(root, file).map_err(|(stage, e)| format!("fails at {stage:?}: {e}"))?;
    // The start pose with the root at the origin gives the height that lifts it to the drop.
    let mut probe = world(&loaded, Some(0.0)).map_err(|(_, e)| e)?;
    let zero = vec![0.0; probe.joints().len()];
    probe
        .set_joint_positions(&zero)
        .map_err(|e| e.to_string())?;
    let links = probe.model().link_names().to_vec();
    let (_, low) = lowest(
        &lowest_points(&loaded.geometry, &probe.link_poses()),
        &links,
    )
    .ok_or("no collision shapes: nothing to stand on")?;
    let start_m = DROP_HEIGHT_M - low;

    let started = std::time::Instant::now();
    let mut world = world(&loaded, Some(start_m)).map_err(|(_, e)| e)?;
    world
        .set_joint_positions(&zero)
        .map_err(|e| e.to_string())?;
    let root_index = world
        .model()
        .link_index(world.model().root_link_name())
        .expect("root link");
    let mut settling_from_m = 0.0;
    for step in 0..LEGGED_STEPS {
        if step == LEGGED_STEPS - 100 {
            settling_from_m = world.link_poses()[root_index].translation.z;
        }
        world.step(&zero);
    }
    let wall = started.elapsed();
    world.check_finite().map_err(|e| format!("diverged: {e}"))?;
    let poses = world.link_poses();
    let root_link = world.model().root_link_name().to_owned();
    let rest_m = poses[root_index].translation.z;
    let (low_link, low_m) =
        lowest(&lowest_points(&loaded.geometry, &poses), &links).expect("shapes");
    if rest_m <= 0.0 || low_m <= -MAX_SINK_M {
        return Err(format!(
            "sank: root `{root_link}` at {rest_m:.4} m, link `{low_link}` at {low_m:.4} m \
             after {} s",
            LEGGED_STEPS as f64 / 1000.0
        ));
    }
    Ok(format!(
        "{}: root `{root_link}` dropped from {start_m:.4} m rests at {rest_m:.4} m, lowest \
         point {low_m:.4} m (`{low_link}`), moved {:.2} mm in the last 100 ms, {} s \
         simulated in {:.2} s",
        file.display(),
        (rest_m - settling_from_m).abs() * 1000.0,
        LEGGED_STEPS as f64 / 1000.0,
        wall.as_secs_f64()
    ))
}
