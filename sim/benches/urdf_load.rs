//! How long a URDF takes to load into the articulated world, and the memory it takes: chains
//! of 1,000 and 5,000 links (the target: 5,000 in at most 2 s and 200 MB), and a branching
//! tree of 5,000. Prints figures; asserts nothing. `cargo bench -p armhil-sim --bench urdf_load`.

use std::time::Instant;

use sim::description::{Description, MissingMeshes, PackagePaths};
use sim::physics::articulated::ArticulatedWorld;
use sim::physics::WorldConfig;

const INERTIAL: &str = r#"<inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial><collision><geometry><box size="0.02 0.02 0.01"/></geometry></collision>"#;

/// A URDF of `links` links; each link's parent is `parent(i)`.
fn urdf(links: usize, parent: impl Fn(usize) -> usize) -> String {
    let mut text = String::from("<?xml version=\"1.0\"?>\n<robot name=\"generated\">\n");
    for i in 0..links {
        text.push_str(&format!("<link name=\"l{i}\">{INERTIAL}</link>\n"));
        if i > 0 {
            text.push_str(&format!(
                "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/><origin xyz=\"0 0 0.01\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
                parent(i)
            ));
        }
    }
    text.push_str("</robot>\n");
    text
}

/// Peak resident memory of this process so far (MB), from /proc.
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn load(name: &str, text: String) {
    let bytes = text.len();
    let start = Instant::now();
    let description = Description::parse(text, PackagePaths::default()).expect("parses");
    let parsed = start.elapsed();
    let geometry = description
        .collision_geometry(MissingMeshes::Refuse)
        .expect("geometry");
    let mut world = ArticulatedWorld::from_description(
        &description,
        &geometry,
        WorldConfig {
            floating_base_height_m: Some(1.0),
            ..WorldConfig::default()
        },
    )
    .expect("world");
    let inertia = world.mass_matrix_diagonal();
    let loaded = start.elapsed();
    let step = Instant::now();
    world.step(&[]);
    println!(
        "{name:<28} {:>7.1} KB  parse {:>7.1} ms  loaded {:>7.1} ms  one step {:>6.2} ms  {} joints  peak RSS {:.0} MB",
        bytes as f64 / 1024.0,
        parsed.as_secs_f64() * 1e3,
        loaded.as_secs_f64() * 1e3,
        step.elapsed().as_secs_f64() * 1e3,
        inertia.len(),
        peak_rss_mb().unwrap_or(f64::NAN),
    );
}

fn main() {
    load("chain of 1,000 links", urdf(1000, |i| i - 1));
    load("chain of 5,000 links", urdf(5000, |i| i - 1));
    load("binary tree of 5,000 links", urdf(5000, |i| (i - 1) / 2));
}
