//! Each link's visual geometry (URDF `<visual>`) as the pages draw it: primitives by their
//! sizes (the page tessellates them), meshes read, simplified and quantised so a whole robot
//! fits inline in one self-contained report.html.
//!
//! # Size budget
//!
//! - each distinct mesh file is simplified to at most [`MAX_MESH_TRIANGLES`] triangles
//!   (vertex clustering, `sim::description::visual`); a file named by several links (a
//!   quadruped's four legs) is sent once;
//! - the meshes as drawn, every use counted, come to at most [`MAX_MODEL_TRIANGLES`]
//!   triangles: when they would exceed it every mesh's cap shrinks in proportion. This bounds
//!   the page's work (a 2D canvas fills about 1 µs a triangle on a CPU: 16,000 keep a
//!   frame near 25 ms) as well as the size;
//! - vertices are quantised to integers 0..=[`QUANT_STEPS`] on a cubic grid over the mesh's
//!   box (1/1023 of its longest side: 0.3 mm on a 30 cm link), indices are plain integers.
//!
//! A triangle costs about 17 bytes of JSON (half a vertex of three ≤ 4-digit numbers, three
//! indices), so a model's meshes stay under about 300 kB whatever the robot: a 30-link robot
//! with meshes yields a report.html well within 3 MB (the trace, at most `MAX_FRAMES` rows,
//! is most of the rest). Primitives are sent as their sizes and tessellated by the page.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use serde::Serialize;
use sim::description::visual::{read_mesh_triangles, TriMesh};
use sim::description::PackagePaths;

/// Most triangles one mesh file is drawn with.
pub const MAX_MESH_TRIANGLES: usize = 1500;
/// Most triangles of a model's meshes as drawn, a mesh counted at each of its uses.
pub const MAX_MODEL_TRIANGLES: usize = 16_000;
/// Quantisation steps along a mesh's longest side: coordinates are integers 0..=1023.
pub const QUANT_STEPS: u32 = 1023;

/// A link's visual geometry, in the visual's frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum GeometryJson {
    /// A box centred on the origin, sides along the axes (m).
    Box {
        /// Side lengths x, y, z.
        size: [f64; 3],
    },
    /// A cylinder along z, centred on the origin.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// A sphere centred on the origin.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A cylinder along z with a half sphere on each end (`length` between their centres).
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylinder part (m).
        length: f64,
    },
    /// A mesh of the model's `meshes`, scaled per axis.
    Mesh {
        /// Index into [`VisualsJson::meshes`].
        mesh: usize,
        /// The URDF's `scale`.
        scale: [f64; 3],
    },
}

/// One `<visual>` of a link.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VisualJson {
    /// The link it moves with.
    pub link: String,
    /// `<origin xyz>` in the link frame (m).
    pub xyz: [f64; 3],
    /// `<origin rpy>` (rad).
    pub rpy: [f64; 3],
    /// What it is.
    pub geometry: GeometryJson,
    /// `<material><color rgba>`, by name from the robot's materials when the visual only
    /// names one; `None`: the mesh's own colour or the page's.
    pub color: Option<[f64; 4]>,
}

/// A mesh, simplified and quantised: vertex `k` is `min + step · positions[3k..3k+3]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshJson {
    /// The file as the URDF names it.
    pub file: String,
    /// The grid's corner (m, in the file's frame).
    pub min: [f64; 3],
    /// The grid's pitch (m).
    pub step: f64,
    /// Vertices, three integers each.
    pub positions: Vec<u16>,
    /// Triangles, three vertex indices each.
    pub triangles: Vec<u32>,
    /// The file's own colour (RGBA), if it has one.
    pub color: Option<[f64; 4]>,
    /// Triangles in the file, before simplification.
    pub source_triangles: usize,
}

/// A link drawn as the stick figure though it has visuals, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FallbackJson {
    /// The link.
    pub link: String,
    /// Why its geometry cannot be drawn (a mesh not found or not readable).
    pub reason: String,
}

/// Every link's visuals, the meshes they use and the links left to the stick figure.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VisualsJson {
    /// Visuals of the links drawn with their geometry.
    pub visuals: Vec<VisualJson>,
    /// Meshes, each once.
    pub meshes: Vec<MeshJson>,
    /// Links with visuals that could not be drawn.
    pub fallbacks: Vec<FallbackJson>,
}

fn round(x: f64, digits: i32) -> f64 {
    let k = 10f64.powi(digits);
    (x * k).round() / k
}

fn rgba(c: &urdf_rs::Vec4) -> Option<[f64; 4]> {
    c.0.iter()
        .all(|x| x.is_finite())
        .then(|| c.0.map(|x| round(x.clamp(0.0, 1.0), 3)))
}

/// A primitive's geometry, or why it cannot be drawn.
fn primitive(g: &urdf_rs::Geometry) -> Result<GeometryJson, String> {
    let ok = |xs: &[f64]| xs.iter().all(|x| x.is_finite() && *x >= 0.0);
    let geometry = match g {
        urdf_rs::Geometry::Box { size } if ok(&size.0) => GeometryJson::Box { size: size.0 },
        urdf_rs::Geometry::Cylinder { radius, length } if ok(&[*radius, *length]) => {
            GeometryJson::Cylinder {
                radius: *radius,
                length: *length,
            }
        }
        urdf_rs::Geometry::Capsule { radius, length } if ok(&[*radius, *length]) => {
            GeometryJson::Capsule {
                radius: *radius,
                length: *length,
            }
        }
        urdf_rs::Geometry::Sphere { radius } if ok(&[*radius]) => {
            GeometryJson::Sphere { radius: *radius }
        }
        urdf_rs::Geometry::Mesh { .. } => unreachable!("meshes are read by the caller"),
        _ => return Err("a primitive with a negative or non-finite size".to_owned()),
    };
    Ok(geometry)
}

/// A mesh read once per file: its triangles, or why not.
type Read = Result<Arc<TriMesh>, String>;

/// A mesh a visual uses: the file as the URDF names it, where it was found, what it holds.
type Used = (String, PathBuf, Arc<TriMesh>);

/// Quantises `mesh` (already simplified) on a grid over its box.
fn quantised(file: &str, mesh: &TriMesh, source_triangles: usize) -> MeshJson {
    let (lo, hi) = mesh.bounds().unwrap_or_default();
    let min = lo.map(|v| round(f64::from(v), 7));
    let side = (0..3)
        .map(|i| f64::from(hi[i]) - min[i])
        .fold(0.0, f64::max);
    // Rounded up so the far corner stays within QUANT_STEPS.
    let step = if side > 0.0 {
        (side / f64::from(QUANT_STEPS) * 1e9).ceil() / 1e9
    } else {
        1.0
    };
    let positions = mesh
        .vertices
        .iter()
        .flat_map(|v| {
            (0..3).map(move |i| {
                ((f64::from(v[i]) - min[i]) / step)
                    .round()
                    .clamp(0.0, f64::from(u16::MAX)) as u16
            })
        })
        .collect();
    MeshJson {
        file: file.to_owned(),
        min,
        step,
        positions,
        triangles: mesh.triangles.iter().flatten().copied().collect(),
        color: mesh.color.map(|c| c.map(|x| round(f64::from(x), 3))),
        source_triangles,
    }
}

/// Every link's visuals. A link whose visuals cannot all be drawn (a mesh not found or not
/// readable, a bad size) is left out whole and listed with the reason; nothing fails.
pub fn visuals_json(robot: &urdf_rs::Robot, paths: &PackagePaths) -> VisualsJson {
    let named: HashMap<&str, [f64; 4]> = robot
        .materials
        .iter()
        .filter_map(|m| Some((m.name.as_str(), rgba(&m.color.as_ref()?.rgba)?)))
        .collect();
    let mut read: HashMap<PathBuf, Read> = HashMap::new();
    let mut out = VisualsJson::default();
    // Meshes used, by file, in first-use order: (file as named, path, mesh).
    let mut used: Vec<Used> = Vec::new();
    for link in &robot.links {
        let mut mine = Vec::new();
        let mut failed = None;
        for v in &link.visual {
            let color = v.material.as_ref().and_then(|m| match &m.color {
                Some(c) => rgba(&c.rgba),
                None => named.get(m.name.as_str()).copied(),
            });
            let geometry = match &v.geometry {
                urdf_rs::Geometry::Mesh { filename, scale } => {
                    let scale = scale.as_ref().map_or([1.0; 3], |s| s.0);
                    let mesh =
                        paths
                            .resolve(filename)
                            .map_err(|e| e.to_string())
                            .and_then(|path| {
                                let mesh = read
                                    .entry(path.clone())
                                    .or_insert_with(|| {
                                        read_mesh_triangles(&path)
                                            .map(Arc::new)
                                            .map_err(|e| e.to_string())
                                    })
                                    .clone()?;
                                Ok((path, mesh))
                            });
                    match mesh {
                        Ok(_) if !scale.iter().all(|s| s.is_finite()) => {
                            Err(format!("mesh `{filename}`: a scale that is not finite"))
                        }
                        Ok((path, mesh)) => {
                            let k = match used.iter().position(|(_, p, _)| *p == path) {
                                Some(k) => k,
                                None => {
                                    used.push((filename.clone(), path, mesh));
                                    used.len() - 1
                                }
                            };
                            Ok(GeometryJson::Mesh { mesh: k, scale })
                        }
                        Err(e) => Err(e),
                    }
                }
                g => primitive(g),
            };
            match geometry {
                Ok(geometry) => mine.push(VisualJson {
                    link: link.name.clone(),
                    xyz: v.origin.xyz.0,
                    rpy: v.origin.rpy.0,
                    geometry,
                    color,
                }),
                Err(reason) => {
                    failed = Some(reason);
                    break;
                }
            }
        }
        match failed {
            Some(reason) => out.fallbacks.push(FallbackJson {
                link: link.name.clone(),
                reason,
            }),
            None => out.visuals.extend(mine),
        }
    }
    // Meshes of links that fell back are not sent: renumber those still used.
    let mut keep: Vec<Option<usize>> = vec![None; used.len()];
    for v in &mut out.visuals {
        if let GeometryJson::Mesh { mesh, .. } = &mut v.geometry {
            let next = keep.iter().flatten().count();
            *mesh = *keep[*mesh].get_or_insert(next);
        }
    }
    let mut kept: Vec<(usize, &Used)> = used
        .iter()
        .enumerate()
        .filter_map(|(k, u)| Some((keep[k]?, u)))
        .collect();
    kept.sort_by_key(|(k, _)| *k);
    let caps: Vec<usize> = kept
        .iter()
        .map(|(_, (_, _, m))| m.triangles.len().min(MAX_MESH_TRIANGLES))
        .collect();
    let mut uses = vec![0usize; kept.len()];
    for v in &out.visuals {
        if let GeometryJson::Mesh { mesh, .. } = v.geometry {
            uses[mesh] += 1;
        }
    }
    let total: usize = caps.iter().zip(&uses).map(|(c, u)| c * u).sum();
    for ((_, (file, _, mesh)), cap) in kept.iter().zip(caps) {
        let cap = if total > MAX_MODEL_TRIANGLES {
            cap * MAX_MODEL_TRIANGLES / total
        } else {
            cap
        };
        let simple = mesh.simplified(cap);
        out.meshes
            .push(quantised(file, &simple, mesh.triangles.len()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn robot(text: &str) -> urdf_rs::Robot {
        urdf_rs::read_from_string(text).unwrap()
    }

    /// An ASCII STL: a tetrahedron with corners at the origin and on each axis at `size`.
    fn tetra_stl(size: f64) -> String {
        let p = [
            [0.0, 0.0, 0.0],
            [size, 0.0, 0.0],
            [0.0, size, 0.0],
            [0.0, 0.0, size],
        ];
        let mut s = String::from("solid t\n");
        for t in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            s.push_str("facet normal 0 0 0\nouter loop\n");
            for k in t {
                let v: [f64; 3] = p[k];
                s.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
            }
            s.push_str("endloop\nendfacet\n");
        }
        s + "endsolid t\n"
    }

    /// A finely tessellated ASCII STL sphere: `n` × 2n quads.
    fn sphere_stl(r: f64, n: usize) -> String {
        let at = |i: usize, j: usize| {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            let ph = std::f64::consts::PI * j as f64 / n as f64;
            [
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos(),
            ]
        };
        let mut s = String::from("solid s\n");
        for i in 0..n {
            for j in 0..2 * n {
                for t in [
                    [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                    [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                ] {
                    s.push_str("facet normal 0 0 0\nouter loop\n");
                    for v in t {
                        s.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
                    }
                    s.push_str("endloop\nendfacet\n");
                }
            }
        }
        s + "endsolid s\n"
    }

    #[test]
    fn primitives_colours_and_a_shared_mesh_once() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(tmp.path().join("leg.stl"), tetra_stl(0.2)).unwrap();
        let urdf = r#"<robot name="r">
  <material name="blue"><color rgba="0 0 1 1"/></material>
  <link name="base"><visual><origin xyz="0 0 0.1" rpy="0 0 1"/><geometry><box size="0.3 0.2 0.1"/></geometry>
    <material name="blue"/></visual>
    <visual><geometry><sphere radius="0.05"/></geometry><material name="m"><color rgba="1 0 0 0.5"/></material></visual></link>
  <link name="a"><visual><geometry><mesh filename="leg.stl" scale="1 -1 2"/></geometry></visual>
    <visual><geometry><cylinder radius="0.02" length="0.3"/></geometry></visual></link>
  <link name="b"><visual><geometry><mesh filename="package://legs/leg.stl"/></geometry></visual>
    <visual><geometry><capsule radius="0.02" length="0.1"/></geometry></visual></link>
  <link name="bare"/>
</robot>"#;
        let paths = PackagePaths {
            urdf_dir: Some(tmp.path().to_owned()),
            packages: vec![("legs".to_owned(), tmp.path().to_owned())],
            ..Default::default()
        };
        let v = visuals_json(&robot(urdf), &paths);
        assert!(v.fallbacks.is_empty(), "{:?}", v.fallbacks);
        assert_eq!(v.visuals.len(), 6);
        assert_eq!(v.visuals[0].color, Some([0.0, 0.0, 1.0, 1.0]), "by name");
        assert_eq!(v.visuals[0].xyz, [0.0, 0.0, 0.1]);
        assert_eq!(v.visuals[1].color, Some([1.0, 0.0, 0.0, 0.5]), "inline");
        assert_eq!(
            v.visuals[2].geometry,
            GeometryJson::Mesh {
                mesh: 0,
                scale: [1.0, -1.0, 2.0]
            }
        );
        // The same file by two names is one mesh.
        assert_eq!(v.meshes.len(), 1);
        assert!(matches!(
            v.visuals[4].geometry,
            GeometryJson::Mesh { mesh: 0, .. }
        ));
        let m = &v.meshes[0];
        assert_eq!((m.triangles.len(), m.positions.len()), (12, 12), "welded");
        assert_eq!(m.source_triangles, 4);
        // Decoded corners are where the file has them.
        let corner = |k: usize| -> [f64; 3] {
            std::array::from_fn(|i| m.min[i] + m.step * f64::from(m.positions[3 * k + i]))
        };
        let far = (0..4).map(corner).fold(0.0f64, |a, c| a.max(c[0]));
        assert!((far - 0.2).abs() < 1e-3, "{far}");
        assert!(m.positions.iter().all(|&q| u32::from(q) <= QUANT_STEPS));
        let json = serde_json::to_value(&v.visuals[5]).unwrap();
        assert_eq!(json["geometry"]["type"], "capsule");
    }

    #[test]
    fn a_link_whose_mesh_cannot_be_read_falls_back_with_the_reason() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(tmp.path().join("bad.stl"), [0xFF; 7]).unwrap();
        let urdf = r#"<robot name="r">
  <link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>
  <link name="lost"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
    <visual><geometry><mesh filename="package://nowhere/m.stl"/></geometry></visual></link>
  <link name="broken"><visual><geometry><mesh filename="bad.stl"/></geometry></visual></link>
  <link name="format"><visual><geometry><mesh filename="m.glb"/></geometry></visual></link>
</robot>"#;
        let paths = PackagePaths {
            urdf_dir: Some(tmp.path().to_owned()),
            ..Default::default()
        };
        let v = visuals_json(&robot(urdf), &paths);
        assert_eq!(v.visuals.len(), 1, "only the base's box");
        assert!(v.meshes.is_empty());
        let why: HashMap<&str, &str> = v
            .fallbacks
            .iter()
            .map(|f| (f.link.as_str(), f.reason.as_str()))
            .collect();
        assert!(why["lost"].contains("no folder is known for package `nowhere`"));
        assert!(why["broken"].contains("bad.stl"), "{}", why["broken"]);
        assert!(why["format"].contains("not found"), "{}", why["format"]);
        // Without paths only absolute names resolve.
        let v = visuals_json(&robot(urdf), &PackagePaths::default());
        assert!(v.fallbacks.iter().any(|f| f.link == "broken"
            && f.reason
                .contains("a relative name, and the URDF has no folder")));
    }

    /// Mesh triangles as a page draws them: each mesh at each of its uses.
    fn drawn_triangles(visuals: &[VisualJson], meshes: &[MeshJson]) -> usize {
        visuals
            .iter()
            .filter_map(|v| match v.geometry {
                GeometryJson::Mesh { mesh, .. } => Some(meshes[mesh].triangles.len() / 3),
                _ => None,
            })
            .sum()
    }

    #[test]
    fn a_mesh_used_by_every_link_counts_at_each_use() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(tmp.path().join("s.stl"), sphere_stl(0.05, 40)).unwrap();
        let mut urdf = String::from("<robot name=\"same\">");
        for k in 0..40 {
            urdf.push_str(&format!(
                "<link name=\"l{k}\"><visual><geometry><mesh filename=\"s.stl\"/></geometry></visual></link>"
            ));
        }
        urdf.push_str("</robot>");
        let paths = PackagePaths {
            urdf_dir: Some(tmp.path().to_owned()),
            ..Default::default()
        };
        let v = visuals_json(&robot(&urdf), &paths);
        assert_eq!((v.meshes.len(), v.visuals.len()), (1, 40));
        let drawn = drawn_triangles(&v.visuals, &v.meshes);
        assert!(drawn <= MAX_MODEL_TRIANGLES, "{drawn}");
        assert!(v.meshes[0].triangles.len() / 3 <= MAX_MODEL_TRIANGLES / 40);
    }

    #[test]
    fn meshes_keep_within_the_budget() {
        let tmp = tempfile::tempdir().unwrap();
        // 30 links, each its own 4800-triangle sphere.
        let mut urdf = String::from("<robot name=\"many\">");
        for k in 0..30 {
            let file = format!("s{k}.stl");
            std::fs::write(
                tmp.path().join(&file),
                sphere_stl(0.05 + 0.001 * k as f64, 40),
            )
            .unwrap();
            urdf.push_str(&format!(
                "<link name=\"l{k}\"><visual><geometry><mesh filename=\"{file}\"/></geometry></visual></link>"
            ));
        }
        urdf.push_str("</robot>");
        let paths = PackagePaths {
            urdf_dir: Some(tmp.path().to_owned()),
            ..Default::default()
        };
        let v = visuals_json(&robot(&urdf), &paths);
        assert_eq!(v.meshes.len(), 30);
        let triangles: usize = v.meshes.iter().map(|m| m.triangles.len() / 3).sum();
        assert!(triangles <= MAX_MODEL_TRIANGLES, "{triangles}");
        assert!(triangles > MAX_MODEL_TRIANGLES / 2, "{triangles}");
        assert!(v
            .meshes
            .iter()
            .all(|m| m.triangles.len() / 3 <= MAX_MESH_TRIANGLES && m.source_triangles == 6400));
        let bytes = serde_json::to_string(&v.meshes).unwrap().len();
        // The doc comment's figure: about 22 bytes a triangle.
        assert!(bytes < 26 * triangles, "{bytes} bytes for {triangles}");
    }

    /// A robot file's report finds the meshes through the file's own folder and `packages:`
    /// (the actuator_group kind's drawing carries its paths), and says which link it could
    /// not draw.
    #[test]
    fn a_robot_files_report_draws_its_meshes_through_its_paths() {
        use crate::harness::result::{ScenarioResult, Verdict};
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("web/tests/fixtures/meshed/meshed_arm.yaml");
        let robot = sim::robot::file::load_robot_file(&file).unwrap().config;
        let settings = crate::devices::actuator_group::model::GroupSettings {
            actuators: Vec::new(),
            buses: Vec::new(),
            robot: Some(robot),
        };
        let drawing = crate::devices::DeviceKind::ActuatorGroup(settings)
            .drawing()
            .unwrap();
        assert!(drawing.paths.is_some());
        let mut run =
            ScenarioResult::not_run("meshed", "meshed.yaml".into(), Verdict::Passed, "virtual");
        run.bench_info.drawing = Some(drawing);
        let html = super::super::report_html(&run);
        let start = html.find("id=\"armhil-data\">").unwrap() + "id=\"armhil-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        let data: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
        let model = &data["model"];
        let files: Vec<&str> = model["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["file"].as_str().unwrap())
            .collect();
        assert_eq!(
            files,
            [
                "package://meshed_fixture/meshes/base.stl",
                "meshes/upper.obj",
                "meshes/wrist.dae"
            ]
        );
        // The COLLADA file's own blue; the OBJ's colour from its <material>.
        assert_eq!(
            model["meshes"][2]["color"],
            serde_json::json!([0.2, 0.4, 0.85, 1.0])
        );
        let kinds: Vec<&str> = model["visuals"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v["geometry"]["type"].as_str().unwrap())
            .collect();
        assert_eq!(kinds, ["mesh", "mesh", "cylinder", "sphere", "mesh"]);
        assert_eq!(
            model["visuals"][1]["color"],
            serde_json::json!([0.9, 0.5, 0.1, 1.0])
        );
        assert_eq!(model["fallbacks"][0]["link"], "tool");
        assert!(model["fallbacks"][0]["reason"]
            .as_str()
            .unwrap()
            .contains("gripper_missing.stl` is not found"));
    }

    /// Public robots' meshes (example-robot-data: STL, OBJ, COLLADA) within the budget, when
    /// `ARMHIL_URDF_CORPUS` names its `share/example-robot-data` folder. Prints each model's
    /// JSON size; `ARMHIL_MODEL_OUT=folder` also writes each model there (for a page).
    #[test]
    fn corpus_robots_draw_within_the_budget() {
        let Some(corpus) = std::env::var_os("ARMHIL_URDF_CORPUS").map(PathBuf::from) else {
            println!("skipped: ARMHIL_URDF_CORPUS is not set");
            return;
        };
        let prefix = corpus
            .parent()
            .and_then(std::path::Path::parent)
            .unwrap()
            .to_owned();
        let paths = PackagePaths {
            ament_prefix_path: vec![prefix],
            ..Default::default()
        };
        let out = std::env::var_os("ARMHIL_MODEL_OUT").map(PathBuf::from);
        for file in [
            "robots/go1_description/urdf/go1.urdf",
            "robots/solo_description/robots/solo12.urdf",
            "robots/talos_data/robots/talos_full_v2.urdf",
            "robots/g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
            "robots/panda_description/urdf/panda.urdf",
        ] {
            let text = std::fs::read_to_string(corpus.join(file)).unwrap();
            let started = std::time::Instant::now();
            let model = super::super::arm::arm_model_with_paths(&text, &paths).unwrap();
            let took = started.elapsed();
            let json = serde_json::to_string(&model).unwrap();
            let triangles: usize = model.meshes.iter().map(|m| m.triangles.len() / 3).sum();
            let source: usize = model.meshes.iter().map(|m| m.source_triangles).sum();
            let drawn = drawn_triangles(&model.visuals, &model.meshes);
            println!(
                "{file}: {} links with visuals, {} meshes, {triangles} of {source} triangles \
                 ({drawn} drawn), {} fallbacks, {} bytes of JSON, {:.2} s",
                model
                    .visuals
                    .iter()
                    .map(|v| &v.link)
                    .collect::<std::collections::HashSet<_>>()
                    .len(),
                model.meshes.len(),
                model.fallbacks.len(),
                json.len(),
                took.as_secs_f64()
            );
            for f in &model.fallbacks {
                println!("  fallback {}: {}", f.link, f.reason);
            }
            assert!(model.fallbacks.is_empty(), "{file}");
            assert!(drawn <= MAX_MODEL_TRIANGLES);
            assert!(json.len() < 400_000, "{file}: {} bytes", json.len());
            if let Some(dir) = &out {
                let name = std::path::Path::new(file).file_stem().unwrap();
                std::fs::write(dir.join(name).with_extension("json"), &json).unwrap();
            }
        }
    }
}
