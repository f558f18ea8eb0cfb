//! The arm drawn by the web pages: joint origins, axes and limits read from a URDF, as JSON,
//! with each link's visual geometry ([`super::visuals`]). The pages compute the forward
//! kinematics themselves (web/common/arm3d.js).

use serde::Serialize;
use sim::description::PackagePaths;

pub use super::visuals::{FallbackJson, GeometryJson, MeshJson, VisualJson};

/// Why a URDF could not be turned into a drawable model.
#[derive(Debug, thiserror::Error)]
pub enum ArmModelError {
    /// The text is not a URDF urdf-rs can read.
    #[error("cannot read the URDF: {message}")]
    Parse {
        /// urdf-rs's message.
        message: String,
    },
    /// A joint's parent link is not reachable from the root (a cycle or a forest).
    #[error("joint `{joint}` is not connected to the root link `{root}`")]
    Disconnected {
        /// The joint.
        joint: String,
        /// The root link found.
        root: String,
    },
}

/// A URDF `<mimic>`: `q = multiplier · q_joint + offset`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MimicJson {
    /// The leader joint.
    pub joint: String,
    /// Multiplier.
    pub multiplier: f64,
    /// Offset (rad or m).
    pub offset: f64,
}

/// One joint of the drawn model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointJson {
    /// URDF name.
    pub name: String,
    /// `revolute`, `continuous`, `prismatic` or `fixed` (others are drawn as fixed).
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Parent link.
    pub parent: String,
    /// Child link.
    pub child: String,
    /// Origin translation in the parent frame, m.
    pub xyz: [f64; 3],
    /// Origin roll, pitch, yaw, rad.
    pub rpy: [f64; 3],
    /// Joint axis in the joint frame.
    pub axis: [f64; 3],
    /// Lower limit (rad or m), `None` when unbounded.
    pub lower: Option<f64>,
    /// Upper limit (rad or m), `None` when unbounded.
    pub upper: Option<f64>,
    /// `<mimic>`, if any.
    pub mimic: Option<MimicJson>,
}

/// The drawn model: joints ordered from the root outwards, and the links' visuals. The visual
/// lists are left out of the JSON when empty (a URDF without `<visual>`: a stick figure).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArmModelJson {
    /// `<robot name>`.
    pub name: String,
    /// The root link.
    pub root: String,
    /// Joints, each after the joint that moves its parent link.
    pub joints: Vec<JointJson>,
    /// Every `<visual>` of the links drawn with their geometry.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub visuals: Vec<VisualJson>,
    /// The meshes the visuals use, simplified and quantised (see [`super::visuals`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<MeshJson>,
    /// Links with visuals that are drawn as the stick figure instead, and why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fallbacks: Vec<FallbackJson>,
}

fn kind_name(kind: &urdf_rs::JointType) -> &'static str {
    match kind {
        urdf_rs::JointType::Revolute => "revolute",
        urdf_rs::JointType::Continuous => "continuous",
        urdf_rs::JointType::Prismatic => "prismatic",
        _ => "fixed",
    }
}

fn joint_json(j: &urdf_rs::Joint) -> JointJson {
    let kind = kind_name(&j.joint_type);
    let bounded = matches!(kind, "revolute" | "prismatic");
    JointJson {
        name: j.name.clone(),
        kind,
        parent: j.parent.link.clone(),
        child: j.child.link.clone(),
        xyz: j.origin.xyz.0,
        rpy: j.origin.rpy.0,
        axis: j.axis.xyz.0,
        lower: bounded.then_some(j.limit.lower),
        upper: bounded.then_some(j.limit.upper),
        mimic: j.mimic.as_ref().map(|m| MimicJson {
            joint: m.joint.clone(),
            multiplier: m.multiplier.unwrap_or(1.0),
            offset: m.offset.unwrap_or(0.0),
        }),
    }
}

/// URDF text and where the files it names are: what [`arm_model`] takes.
#[derive(Debug, Clone)]
pub struct UrdfSource<'a> {
    /// The URDF text.
    pub text: &'a str,
    /// Where its meshes are looked for.
    pub paths: std::borrow::Cow<'a, PackagePaths>,
}

/// Text alone: meshes, if any, must have absolute names (the bundled arms have none).
impl<'a> From<&'a str> for UrdfSource<'a> {
    fn from(text: &'a str) -> Self {
        Self {
            text,
            paths: std::borrow::Cow::Owned(PackagePaths::default()),
        }
    }
}

impl<'a> From<(&'a str, &'a PackagePaths)> for UrdfSource<'a> {
    fn from((text, paths): (&'a str, &'a PackagePaths)) -> Self {
        Self {
            text,
            paths: std::borrow::Cow::Borrowed(paths),
        }
    }
}

impl<'a> From<(&'a str, PackagePaths)> for UrdfSource<'a> {
    fn from((text, paths): (&'a str, PackagePaths)) -> Self {
        Self {
            text,
            paths: std::borrow::Cow::Owned(paths),
        }
    }
}

/// The drawable model of a URDF: `arm_model(text)` for a bundled arm, `arm_model((text,
/// paths))` for a robot whose meshes are found through `paths` ([`arm_model_with_paths`]).
pub fn arm_model<'a>(urdf: impl Into<UrdfSource<'a>>) -> Result<ArmModelJson, ArmModelError> {
    let source = urdf.into();
    arm_model_with_paths(source.text, &source.paths)
}

/// The drawable model of a URDF, its meshes found through `paths` (a robot's `urdf_paths`).
/// A mesh that cannot be found or read leaves its link to the stick figure, said in
/// [`ArmModelJson::fallbacks`]; only a URDF that cannot be read at all is an error.
pub fn arm_model_with_paths(
    urdf: &str,
    paths: &PackagePaths,
) -> Result<ArmModelJson, ArmModelError> {
    let robot = urdf_rs::read_from_string(urdf).map_err(|e| ArmModelError::Parse {
        message: e.to_string(),
    })?;
    let is_child = |link: &str| robot.joints.iter().any(|j| j.child.link == link);
    let root = robot
        .links
        .iter()
        .map(|l| l.name.clone())
        .find(|l| !is_child(l))
        .unwrap_or_default();
    // Breadth-first from the root: every joint after the one that places its parent link.
    let mut placed = vec![root.clone()];
    let mut joints = Vec::with_capacity(robot.joints.len());
    let mut i = 0;
    while i < placed.len() {
        let link = placed[i].clone();
        for j in robot.joints.iter().filter(|j| j.parent.link == link) {
            joints.push(joint_json(j));
            placed.push(j.child.link.clone());
        }
        i += 1;
    }
    if let Some(j) = robot
        .joints
        .iter()
        .find(|j| !joints.iter().any(|k| k.name == j.name))
    {
        return Err(ArmModelError::Disconnected {
            joint: j.name.clone(),
            root,
        });
    }
    let visuals = super::visuals::visuals_json(&robot, paths);
    Ok(ArmModelJson {
        name: robot.name,
        root,
        joints,
        visuals: visuals.visuals,
        meshes: visuals.meshes,
        fallbacks: visuals.fallbacks,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn piper_joints_come_root_first_with_their_urdf_origins() {
        let model = arm_model(sim::piper::BUNDLED_URDF).unwrap();
        assert_eq!(model.root, "base_link");
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        let pos = |n: &str| names.iter().position(|x| *x == n).unwrap();
        assert!(pos("joint1") < pos("joint2") && pos("joint2") < pos("joint3"));
        assert!(pos("joint6") < pos("joint7"));
        let j3 = &model.joints[pos("joint3")];
        assert!((j3.xyz[0] - 0.28503).abs() < 1e-9);
        assert_eq!(j3.kind, "revolute");
        let j8 = &model.joints[pos("joint8")];
        assert_eq!(j8.mimic.as_ref().map(|m| m.multiplier), Some(-1.0));
        // Every joint's parent is the root or the child of an earlier joint.
        for (i, j) in model.joints.iter().enumerate() {
            assert!(
                j.parent == model.root || model.joints[..i].iter().any(|k| k.child == j.parent),
                "{} comes before its parent",
                j.name
            );
        }
    }

    /// web/tests/fixtures/piper_fk.json: the model the pages draw and link positions the
    /// emulator's own kinematics (sim's `ArmModel::link_poses`) gives for a few poses. The
    /// page's forward kinematics is tested against it (`node --test web/tests/unit`).
    fn piper_fk_fixture() -> String {
        let model = arm_model(sim::piper::BUNDLED_URDF).unwrap();
        let sim_model = sim::physics::ArmModel::from_urdf_str(sim::piper::BUNDLED_URDF).unwrap();
        let poses_deg: [([f64; 6], f64); 3] = [
            ([0.0; 6], 0.0),
            ([30.0, 60.0, -45.0, 20.0, -30.0, 90.0], 0.05),
            ([-100.0, 150.0, -160.0, -80.0, 70.0, -170.0], 0.02),
        ];
        let cases: Vec<serde_json::Value> = poses_deg
            .iter()
            .map(|(deg, gripper_m)| {
                let mut q: Vec<f64> = deg.iter().map(|d: &f64| d.to_radians()).collect();
                q.extend([gripper_m / 2.0, -gripper_m / 2.0]);
                let poses = sim_model.link_poses(&q).unwrap();
                let links: serde_json::Map<String, serde_json::Value> = sim_model
                    .link_names()
                    .iter()
                    .zip(&poses)
                    .map(|(name, p)| {
                        let v = p.translation.vector;
                        let r = |x: f64| (x * 1e9).round() / 1e9;
                        (name.clone(), serde_json::json!([r(v.x), r(v.y), r(v.z)]))
                    })
                    .collect();
                serde_json::json!({"deg": deg, "gripper_m": gripper_m, "links": links})
            })
            .collect();
        let doc = serde_json::json!({"model": model, "cases": cases});
        serde_json::to_string_pretty(&doc).unwrap() + "\n"
    }

    #[test]
    fn the_page_fk_fixture_is_current() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("web/tests/fixtures/piper_fk.json");
        let want = piper_fk_fixture();
        if std::env::var_os("ARMHIL_UPDATE_WEB_FIXTURES").is_some() {
            std::fs::write(&path, &want).unwrap();
        }
        let have = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            have == want,
            "{} is stale: run with ARMHIL_UPDATE_WEB_FIXTURES=1",
            path.display()
        );
    }

    #[test]
    fn a_live_view_finds_a_robots_meshes_where_its_file_said() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(
            tmp.path().join("m.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
        )
        .unwrap();
        let urdf = r#"<robot name="live_paths_test"><link name="a"><visual><geometry>
            <mesh filename="m.obj"/></geometry></visual></link></robot>"#;
        // Text alone: a relative name has no folder to start from.
        let alone = arm_model(urdf).unwrap();
        assert!(alone.visuals.is_empty() && alone.fallbacks.len() == 1);
        let paths = PackagePaths {
            urdf_dir: Some(tmp.path().to_owned()),
            ..Default::default()
        };
        let model = arm_model((urdf, &paths)).unwrap();
        assert_eq!((model.visuals.len(), model.meshes.len()), (1, 1));
        // Without visuals the JSON is as it always was.
        let piper = serde_json::to_value(arm_model(sim::piper::BUNDLED_URDF).unwrap()).unwrap();
        assert!(piper.get("visuals").is_none() && piper.get("fallbacks").is_none());
    }

    #[test]
    fn bad_urdf_is_an_error() {
        assert!(matches!(
            arm_model("<robot"),
            Err(ArmModelError::Parse { .. })
        ));
    }
}
