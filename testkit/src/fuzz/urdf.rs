//! The URDF reader behind robot files: checks with line numbers, urdf-rs, the model and the
//! articulated world.

use sim::description::{Description, MissingMeshes, PackagePaths};
use sim::physics::articulated::ArticulatedWorld;
use sim::physics::WorldConfig;

/// Arbitrary text as a robot's URDF: checked, parsed, its collision geometry read (no folder:
/// only absolute mesh paths resolve, and a missing one is an error), built into a floating
/// world and stepped once.
///
/// Asserts: no panic (limits, NaN, nesting, inertias, names, trees are refused with an error),
/// every error names a line in the text or none, and a world that builds takes a step.
pub fn urdf_reader(data: &[u8]) {
    let text = String::from_utf8_lossy(data).into_owned();
    let lines = text.lines().count().max(1);
    let description = match Description::parse(text, PackagePaths::default()) {
        Ok(d) => d,
        Err(e) => {
            assert!(e.line.is_none_or(|l| (1..=lines + 1).contains(&l)), "{e}");
            let _ = e.to_string();
            return;
        }
    };
    let _ = description.unused_summary();
    let Ok(geometry) = description.collision_geometry(MissingMeshes::Refuse) else {
        return;
    };
    let config = WorldConfig {
        floating_base_height_m: Some(1.0),
        ..WorldConfig::default()
    };
    if let Ok(mut world) = ArticulatedWorld::from_description(&description, &geometry, config) {
        world.step(&[]);
        let _ = world.check_finite();
        let _ = world.mass_matrix_diagonal();
    }
}
