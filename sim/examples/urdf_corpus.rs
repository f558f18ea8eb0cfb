//! Loads every `*.urdf` of a robot-description corpus (example-robot-data 6.0.0 from PyPI)
//! into the articulated-body world and prints a markdown table: one row per file with its
//! links, movable joints, collision meshes and their hull points, the load time (parse,
//! collision geometry, world), the legged robots' rest height after falling 3 s unpowered,
//! and how fast the unpowered world steps.
//!
//! `cargo run -p armhil-sim --release --example urdf_corpus -- CORPUS`, where `CORPUS` is
//! `…/cmeel.prefix/share/example-robot-data` (or set `ARMHIL_URDF_CORPUS`). Run it in release:
//! the times are what it measures.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use nalgebra::Isometry3;
use sim::description::{
    CollisionGeometry, CollisionShape, Description, MissingMeshes, PackagePaths,
};
use sim::physics::articulated::ArticulatedWorld;
use sim::physics::WorldConfig;

/// The variable naming the corpus when no argument does.
const CORPUS_ENV: &str = "ARMHIL_URDF_CORPUS";

/// The legged robots dropped on the ground (relative to the corpus).
const LEGGED: &[&str] = &[
    "robots/a1_description/urdf/a1.urdf",
    "robots/anymal_b_simple_description/robots/anymal.urdf",
    "robots/anymal_c_simple_description/urdf/anymal.urdf",
    "robots/g1_description/urdf/g1_29dof_rev_1_0.urdf",
    "robots/go1_description/urdf/go1.urdf",
    "robots/solo_description/robots/solo12.urdf",
    "robots/talos_data/robots/talos_reduced.urdf",
];

/// Steps (1 ms) of the fixed-base world timed for its speed.
const SPEED_STEPS: u32 = 1000;
/// Steps (1 ms) of a legged robot's unpowered fall.
const DROP_STEPS: u32 = 3000;
/// Height of the lowest collision point above the ground when a legged robot is let go (m).
const DROP_HEIGHT_M: f64 = 0.02;

/// One file's row.
#[derive(Default)]
struct Row {
    /// The file, relative to the corpus.
    file: String,
    /// Links (once parsed).
    links: Option<usize>,
    /// Movable joints (once the world is built).
    joints: Option<usize>,
    /// Collision meshes (once hulled).
    meshes: Option<usize>,
    /// Their hull points, all together.
    hull_points: Option<usize>,
    /// Parse, collision geometry and world.
    load: Duration,
    /// Rest height of the root (m) and the lowest collision point (m), legged robots only.
    rest: Option<(f64, f64)>,
    /// Fixed-base speed, × real time.
    fixed_speed: Option<f64>,
    /// Floating-base speed, × real time (legged robots).
    floating_speed: Option<f64>,
    /// What failed, if anything.
    problem: Option<String>,
}

/// Prints the table of the corpus named by the first argument or `ARMHIL_URDF_CORPUS`.
fn main() {
    let root = std::env::args_os()
        .nth(1)
        .or_else(|| std::env::var_os(CORPUS_ENV))
        .map(PathBuf::from);
    let Some(root) = root else {
        eprintln!(
            "usage: urdf_corpus CORPUS (or {CORPUS_ENV}=CORPUS), CORPUS being \
             …/cmeel.prefix/share/example-robot-data of `pip install example-robot-data==6.0.0`"
        );
        std::process::exit(2);
    };
    let files = match urdf_files(&root) {
        Ok(files) if !files.is_empty() => files,
        Ok(_) => {
            eprintln!("no *.urdf below {}", root.display());
            std::process::exit(2);
        }
        Err(e) => {
            eprintln!("cannot list {}: {e}", root.display());
            std::process::exit(2);
        }
    };

    println!(
        "| file | links | movable joints | collision meshes | hull points | load ms | \
         rest height m (3 s unpowered) | × real time fixed | × real time floating | problem |"
    );
    println!("|---|--:|--:|--:|--:|--:|--:|--:|--:|---|");
    let mut rows = Vec::new();
    for file in &files {
        let row = measure(&root, file);
        print_row(&row);
        rows.push(row);
    }

    println!();
    let loaded: Vec<&Row> = rows.iter().filter(|r| r.fixed_speed.is_some()).collect();
    println!(
        "{} files, {} load and run, {} fail",
        rows.len(),
        loaded.len(),
        rows.len() - loaded.len()
    );
    if let Some(slowest) = rows.iter().max_by_key(|r| r.load) {
        println!("slowest load: {:.1} ms, {}", ms(slowest.load), slowest.file);
    }
    let total: Duration = rows.iter().map(|r| r.load).sum();
    println!("all loads: {:.1} ms", ms(total));
    if let Some(slowest) = loaded
        .iter()
        .filter_map(|r| r.fixed_speed.map(|s| (s, &r.file)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
    {
        println!(
            "slowest fixed-base world: {:.0}× real time, {}",
            slowest.0, slowest.1
        );
    }
}

/// `d` in milliseconds.
fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}

/// Prints one table row.
fn print_row(row: &Row) {
    let or_dash = |v: Option<String>| v.unwrap_or_else(|| "—".to_owned());
    let count = |n: Option<usize>| or_dash(n.map(|n| n.to_string()));
    println!(
        "| {} | {} | {} | {} | {} | {:.1} | {} | {} | {} | {} |",
        row.file,
        count(row.links),
        count(row.joints),
        count(row.meshes),
        count(row.hull_points),
        ms(row.load),
        or_dash(
            row.rest
                .map(|(rest, low)| format!("{rest:.3} (lowest point {low:.3})"))
        ),
        or_dash(row.fixed_speed.map(|s| format!("{s:.0}"))),
        or_dash(row.floating_speed.map(|s| format!("{s:.0}"))),
        or_dash(row.problem.as_ref().map(|p| p.replace('|', "\\|"))),
    );
}

/// Every `*.urdf` below `root`, relative to it, sorted.
fn urdf_files(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    let mut folders = vec![root.to_owned()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder)? {
            let entry = entry?;
            let path = entry.path();
            if entry.file_type()?.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "urdf") {
                if let Ok(relative) = path.strip_prefix(root) {
                    found.push(relative.to_owned());
                }
            }
        }
    }
    found.sort();
    Ok(found)
}

/// Where the corpus's URDFs find their meshes: `package://example-robot-data/…` through the
/// ament prefix two folders above the corpus, b1's own package name mapped to its folder.
fn package_paths(root: &Path, file: &Path) -> PackagePaths {
    let prefix = root.parent().and_then(Path::parent).unwrap_or(root);
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

/// A world fixed (`None`) or free, its root `height` above the ground.
fn config(height: Option<f64>) -> WorldConfig {
    WorldConfig {
        floating_base_height_m: height,
        ..WorldConfig::default()
    }
}

/// Loads, times and runs one file.
fn measure(root: &Path, file: &Path) -> Row {
    let mut row = Row {
        file: file.display().to_string(),
        ..Row::default()
    };
    let started = Instant::now();
    let loaded = load(root, file, &mut row);
    row.load = started.elapsed();
    let (description, geometry, mut world) = match loaded {
        Ok(loaded) => loaded,
        Err(problem) => {
            // Paths inside the corpus, relative: the table stays readable.
            let inside = format!("{}/", root.display());
            row.problem = Some(short(&problem.replace(&inside, "")));
            return row;
        }
    };

    let zero = vec![0.0; world.joints().len()];
    if let Err(e) = world.set_joint_positions(&zero) {
        row.problem = Some(short(&e.to_string()));
        return row;
    }
    let started = Instant::now();
    for _ in 0..SPEED_STEPS {
        world.step(&zero);
    }
    let wall = started.elapsed();
    if let Err(e) = world.check_finite() {
        row.problem = Some(format!("fixed base: {}", short(&e.to_string())));
        return row;
    }
    row.fixed_speed = Some(speed(SPEED_STEPS, wall));

    if LEGGED.iter().any(|l| Path::new(l) == file) {
        match drop_on_the_ground(&description, &geometry) {
            Ok((rest, low, floating)) => {
                row.rest = Some((rest, low));
                row.floating_speed = Some(floating);
            }
            Err(problem) => row.problem = Some(format!("floating base: {problem}")),
        }
    }
    row
}

/// Reads, parses and hulls `file` and builds its fixed-base world, counting into `row` what
/// each stage makes known (links, then meshes, then joints).
fn load(
    root: &Path,
    file: &Path,
    row: &mut Row,
) -> Result<(Description, CollisionGeometry, ArticulatedWorld), String> {
    let path = root.join(file);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("read: {e}"))?;
    let description =
        Description::parse(text, package_paths(root, &path)).map_err(|e| format!("parse: {e}"))?;
    row.links = Some(description.robot().links.len());
    let geometry = description
        .collision_geometry(MissingMeshes::Refuse)
        .map_err(|e| format!("collision geometry: {e}"))?;
    let hulls = geometry.shapes.iter().filter_map(|s| match &s.shape {
        CollisionShape::Hull { points_m, .. } => Some(points_m.len()),
        _ => None,
    });
    row.meshes = Some(hulls.clone().count());
    row.hull_points = Some(hulls.sum());
    let world = ArticulatedWorld::from_description(&description, &geometry, config(None))
        .map_err(|e| format!("world: {e}"))?;
    row.joints = Some(world.joints().len());
    Ok((description, geometry, world))
}

/// × real time: `steps` of 1 ms in `wall`.
fn speed(steps: u32, wall: Duration) -> f64 {
    f64::from(steps) / 1000.0 / wall.as_secs_f64().max(1e-9)
}

/// An error's first line, at most 200 characters.
fn short(text: &str) -> String {
    let line = text.lines().next().unwrap_or_default();
    match line.char_indices().nth(200) {
        Some((at, _)) => format!("{}…", &line[..at]),
        None => line.to_owned(),
    }
}

/// Drops the robot: joints at 0 (clamped to their limits), its lowest collision point
/// [`DROP_HEIGHT_M`] above the ground, no torque, [`DROP_STEPS`] ms. The root's height and
/// the lowest collision point's at the end (m), and the speed (× real time).
fn drop_on_the_ground(
    description: &Description,
    geometry: &CollisionGeometry,
) -> Result<(f64, f64, f64), String> {
    let mut probe = ArticulatedWorld::from_description(description, geometry, config(Some(0.0)))
        .map_err(|e| e.to_string())?;
    let zero = vec![0.0; probe.joints().len()];
    probe
        .set_joint_positions(&zero)
        .map_err(|e| e.to_string())?;
    let start = lowest_z(geometry, &probe.link_poses()).ok_or("no collision shapes")?;

    let mut world = ArticulatedWorld::from_description(
        description,
        geometry,
        config(Some(DROP_HEIGHT_M - start)),
    )
    .map_err(|e| e.to_string())?;
    world
        .set_joint_positions(&zero)
        .map_err(|e| e.to_string())?;
    let started = Instant::now();
    for _ in 0..DROP_STEPS {
        world.step(&zero);
    }
    let wall = started.elapsed();
    world.check_finite().map_err(|e| e.to_string())?;
    let poses = world.link_poses();
    let root = world
        .model()
        .link_index(world.model().root_link_name())
        .ok_or("no root link")?;
    let low = lowest_z(geometry, &poses).ok_or("no collision shapes")?;
    Ok((poses[root].translation.z, low, speed(DROP_STEPS, wall)))
}

/// The lowest point (z, m) of all collision shapes at the link poses `poses`.
fn lowest_z(geometry: &CollisionGeometry, poses: &[Isometry3<f64>]) -> Option<f64> {
    geometry.lowest_point(poses).map(|(_, z)| z)
}
