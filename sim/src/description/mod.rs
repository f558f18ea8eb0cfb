//! A robot as its owner describes it: the URDF text as published, checked with line numbers
//! before it is parsed, the meshes it names found the way ROS finds them, and what it holds
//! that armhil does not simulate said once.
//!
//! - `checks`: what urdf-rs accepts but the physics cannot run (limits, non-finite numbers,
//!   inertias, duplicate names, nesting), each at its line;
//! - [`packages`]: `package://`, relative and `file://` names → files;
//! - [`mesh`]: STL, OBJ and COLLADA files → points, bounded and cached;
//! - [`hull`]: points → convex-hull contact points;
//! - [`collision`]: every link's collision shapes for the physics;
//! - `unused`: the one summary line of what is not simulated.

mod checks;
pub mod collision;
pub mod hull;
pub mod mesh;
pub mod packages;
mod unused;
pub mod visual;

pub use checks::{MAX_XML_DEPTH, MAX_XML_ELEMENTS};
pub use collision::{CollisionGeometry, CollisionShape, LinkShape, MissingMeshes};
pub use packages::PackagePaths;

/// A problem in a URDF, at its line when known.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{message}", line.map(|l| format!("line {l}: ")).unwrap_or_default())]
pub struct DescriptionError {
    /// 1-based line in the URDF.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl DescriptionError {
    pub(crate) fn at(line: Option<usize>, message: impl Into<String>) -> Self {
        Self {
            line,
            message: message.into(),
        }
    }
}

/// A checked, parsed URDF and where its files are.
#[derive(Debug, Clone)]
pub struct Description {
    text: String,
    robot: urdf_rs::Robot,
    paths: PackagePaths,
}

impl Description {
    /// Checks and parses URDF text; `paths` says where the files it names are.
    pub fn parse(text: String, paths: PackagePaths) -> Result<Self, DescriptionError> {
        let doc = checks::check_urdf_text(&text)?;
        // urdf-rs refuses a `<texture/>` without `filename`, which ROS's own parser takes
        // (published robots have them); textures are not simulated, so they are cut out of
        // what urdf-rs reads. Line numbers in messages still come from the text as given.
        let textures: Vec<std::ops::Range<usize>> = doc
            .descendants()
            .filter(|n| n.has_tag_name("texture") && n.attribute("filename").is_none())
            .map(|n| n.range())
            .collect();
        drop(doc);
        let parsed = if textures.is_empty() {
            urdf_rs::read_from_string(&text)
        } else {
            let mut kept = String::with_capacity(text.len());
            let mut from = 0;
            for range in textures {
                kept.push_str(&text[from..range.start]);
                from = range.end;
            }
            kept.push_str(&text[from..]);
            urdf_rs::read_from_string(&kept)
        };
        let robot = parsed.map_err(|e| DescriptionError::at(None, format!("invalid URDF: {e}")))?;
        Ok(Self { text, robot, paths })
    }

    /// Checks and parses URDF text and reads its collision geometry (a mesh that is not
    /// found refused): what a physics world is built from, as one [`crate::physics::PhysicsError`].
    pub fn load_for_physics(
        text: String,
        paths: PackagePaths,
    ) -> Result<(Self, CollisionGeometry), crate::physics::PhysicsError> {
        let parse = |e: DescriptionError| crate::physics::PhysicsError::Parse {
            message: e.to_string(),
        };
        let description = Self::parse(text, paths).map_err(parse)?;
        let geometry = description
            .collision_geometry(MissingMeshes::Refuse)
            .map_err(parse)?;
        Ok((description, geometry))
    }

    /// The URDF text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The parsed URDF.
    pub fn robot(&self) -> &urdf_rs::Robot {
        &self.robot
    }

    /// Where its files are looked for.
    pub fn paths(&self) -> &PackagePaths {
        &self.paths
    }

    /// The first line whose text mentions `needle` (a mesh's file name), for messages.
    pub(crate) fn line_mentioning(&self, needle: &str) -> Option<usize> {
        self.text
            .lines()
            .position(|l| l.contains(needle))
            .map(|i| i + 1)
    }
}
