//! Meshes as the 3D views draw them: a mesh file (STL binary and ASCII, OBJ, COLLADA) read into
//! vertices and triangles through the bounded reader, and simplified to a triangle budget by
//! vertex clustering, so a page can carry a whole robot inline.
//!
//! The physics reads the same files into points ([`super::mesh`]); the views need faces.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::mesh::{load_scene, MeshError};

/// A triangle mesh in its file's frame and unit (metres for STL and OBJ; COLLADA's
/// `<unit meter>` applied, its `<up_axis>` not, as [`super::mesh`] reads it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// The file's own diffuse colour (RGBA, 0–1), when it names one: a COLLADA material or
    /// an OBJ's only material. With several, that of the part with the most triangles.
    pub color: Option<[f32; 4]>,
}

/// Reads the triangles of the mesh file at `path` (format from its content and extension).
/// Every part of the file is kept, in one vertex list; faces naming a vertex the file lacks
/// are dropped.
pub fn read_mesh_triangles(path: &Path) -> Result<TriMesh, MeshError> {
    let fail = |message: String| MeshError {
        path: path.to_owned(),
        message,
    };
    // Parts are joined here rather than by mesh-loader's `merge_meshes`, which offsets each
    // part's indices by its last face's last index instead of its vertex count.
    let scene = load_scene(path)?;
    let mut out = TriMesh::default();
    // COLLADA gives one material per part, in order; OBJ's table does not say which part uses
    // which, so only a lone material is taken.
    let per_part = scene.materials.len() == scene.meshes.len();
    let lone = (scene.materials.len() == 1)
        .then(|| scene.materials[0].color.diffuse)
        .flatten();
    let mut best_part = 0;
    for (k, mesh) in scene.meshes.iter().enumerate() {
        let base = out.vertices.len();
        for v in &mesh.vertices {
            if !v.iter().all(|c| c.is_finite()) {
                return Err(fail("a vertex is not a finite number".to_owned()));
            }
            out.vertices.push(*v);
        }
        let count = mesh.vertices.len() as u64;
        let before = out.triangles.len();
        let Ok(base) = u32::try_from(base) else {
            return Err(fail("more than 4 billion vertices".to_owned()));
        };
        out.triangles.extend(
            mesh.faces
                .iter()
                .filter(|f| f.iter().all(|&i| u64::from(i) < count))
                .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
        );
        let added = out.triangles.len() - before;
        let color = if per_part {
            scene.materials[k].color.diffuse
        } else {
            lone
        };
        if let Some(c) = color.filter(|c| c.iter().all(|x| x.is_finite())) {
            if added > best_part || out.color.is_none() {
                best_part = added;
                out.color = Some(c.map(|x| x.clamp(0.0, 1.0)));
            }
        }
    }
    if out.triangles.is_empty() {
        return Err(fail("no triangles".to_owned()));
    }
    Ok(out)
}

/// The finest grid [`TriMesh::simplified`] clusters on: cells of 1/4096 of the mesh's
/// longest side (finer than a page draws; it welds an STL's repeated corners).
pub const FINEST_GRID: u32 = 4096;

impl TriMesh {
    /// The smallest box holding every vertex: `(min, max)`, `None` without vertices.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.vertices.first()?;
        Some(self.vertices.iter().fold((first, first), |(lo, hi), v| {
            (
                [lo[0].min(v[0]), lo[1].min(v[1]), lo[2].min(v[2])],
                [hi[0].max(v[0]), hi[1].max(v[1]), hi[2].max(v[2])],
            )
        }))
    }

    /// The mesh with at most `max_triangles` triangles, by vertex clustering: vertices are
    /// gathered in the cells of a cubic grid over the mesh's box and each cell's become one,
    /// at their mean; triangles left with fewer than three corners, and repeats, go. The
    /// grid is the finest (at most [`FINEST_GRID`] cells along the longest side) that keeps
    /// within the cap, so a small mesh is only welded. Only vertices still used are kept.
    pub fn simplified(&self, max_triangles: usize) -> TriMesh {
        let welded = self.clustered(FINEST_GRID);
        if welded.triangles.len() <= max_triangles {
            return welded;
        }
        // The triangle count grows with the grid's resolution, nearly monotonically: search
        // for the finest grid within the cap, then step down past any bump.
        let (mut lo, mut hi) = (1u32, FINEST_GRID);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if welded.clustered(mid).triangles.len() <= max_triangles {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let mut cells = lo;
        loop {
            let mesh = welded.clustered(cells);
            if mesh.triangles.len() <= max_triangles || cells == 1 {
                return mesh;
            }
            cells -= 1;
        }
    }

    /// Vertex clustering on a grid of `cells` cells along the longest side of the box.
    fn clustered(&self, cells: u32) -> TriMesh {
        let Some((lo, hi)) = self.bounds() else {
            return TriMesh {
                color: self.color,
                ..TriMesh::default()
            };
        };
        let side = (0..3).map(|i| hi[i] - lo[i]).fold(0.0f32, f32::max);
        let cell = if side > 0.0 { side / cells as f32 } else { 1.0 };
        let key = |v: &[f32; 3]| -> [u32; 3] {
            std::array::from_fn(|i| (((v[i] - lo[i]) / cell) as u32).min(cells - 1))
        };
        let mut cluster_of_key: HashMap<[u32; 3], u32> = HashMap::new();
        let cluster: Vec<u32> = self
            .vertices
            .iter()
            .map(|v| {
                let next = cluster_of_key.len() as u32;
                *cluster_of_key.entry(key(v)).or_insert(next)
            })
            .collect();
        let mut sums = vec![([0.0f64; 3], 0u32); cluster_of_key.len()];
        for (v, &c) in self.vertices.iter().zip(&cluster) {
            let s = &mut sums[c as usize];
            for (sum, x) in s.0.iter_mut().zip(v) {
                *sum += f64::from(*x);
            }
            s.1 += 1;
        }
        // Keep triangles with three distinct corners, once each (either winding).
        let mut seen = HashSet::new();
        let mut new_index: Vec<u32> = vec![u32::MAX; sums.len()];
        let mut out = TriMesh {
            color: self.color,
            ..TriMesh::default()
        };
        for t in &self.triangles {
            let c = t.map(|i| cluster[i as usize]);
            if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
                continue;
            }
            let mut sorted = c;
            sorted.sort_unstable();
            if !seen.insert(sorted) {
                continue;
            }
            let tri = c.map(|k| {
                let slot = &mut new_index[k as usize];
                if *slot == u32::MAX {
                    *slot = out.vertices.len() as u32;
                    let (sum, n) = sums[k as usize];
                    out.vertices
                        .push(sum.map(|s| (s / f64::from(n.max(1))) as f32));
                }
                *slot
            });
            out.triangles.push(tri);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::mesh::tests::{box_stl_ascii, box_stl_binary};
    use super::*;

    /// A UV sphere of radius `r`: `rings` × `segments` quads, poles as fans.
    fn sphere(r: f32, rings: u32, segments: u32) -> TriMesh {
        let mut m = TriMesh::default();
        for i in 0..=rings {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segments {
                let phi = 2.0 * std::f32::consts::PI * j as f32 / segments as f32;
                m.vertices.push([
                    r * theta.sin() * phi.cos(),
                    r * theta.sin() * phi.sin(),
                    r * theta.cos(),
                ]);
            }
        }
        let at = |i: u32, j: u32| i * segments + j % segments;
        for i in 0..rings {
            for j in 0..segments {
                m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        m
    }

    fn radius_range(m: &TriMesh) -> (f32, f32) {
        m.vertices.iter().fold((f32::MAX, 0.0f32), |(lo, hi), v| {
            let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            (lo.min(r), hi.max(r))
        })
    }

    #[test]
    fn stl_boxes_read_as_twelve_triangles_on_eight_corners_once_welded() {
        let tmp = tempfile::tempdir().unwrap();
        let ascii = tmp.path().join("a.stl");
        let binary = tmp.path().join("b.STL");
        std::fs::write(&ascii, box_stl_ascii([0.1, 0.2, 0.3])).unwrap();
        std::fs::write(&binary, box_stl_binary([0.1, 0.2, 0.3])).unwrap();
        for path in [ascii, binary] {
            let mesh = read_mesh_triangles(&path).unwrap();
            assert_eq!(mesh.triangles.len(), 12, "{path:?}");
            let (lo, hi) = mesh.bounds().unwrap();
            assert!((lo[2] + 0.3).abs() < 1e-6 && (hi[1] - 0.2).abs() < 1e-6);
            let welded = mesh.simplified(1000);
            assert_eq!(welded.triangles.len(), 12, "{path:?}");
            assert_eq!(welded.vertices.len(), 8, "{path:?}");
        }
    }

    #[test]
    fn obj_and_collada_parts_keep_their_own_vertices() {
        let tmp = tempfile::tempdir().unwrap();
        let obj = tmp.path().join("t.obj");
        std::fs::write(
            &obj,
            "v 0 0 0\nv 1 0 0\nv 0 2 0\nv 0 0 3\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
        )
        .unwrap();
        let mesh = read_mesh_triangles(&obj).unwrap();
        assert_eq!(mesh.triangles.len(), 4);
        assert_eq!(mesh.bounds().unwrap().1, [1.0, 2.0, 3.0]);

        // Two geometries of four vertices each, the second with a red material.
        let geometry = |id: &str, offset: f32, material: &str| {
            let p: Vec<String> = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]]
                .iter()
                .flat_map(|v: &[f32; 3]| [v[0] + offset, v[1], v[2]])
                .map(|c| c.to_string())
                .collect();
            format!(
                r##"<geometry id="{id}"><mesh>
  <source id="{id}-pos"><float_array id="{id}-arr" count="12">{}</float_array>
    <technique_common><accessor source="#{id}-arr" count="4" stride="3">
      <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
    </accessor></technique_common></source>
  <vertices id="{id}-vtx"><input semantic="POSITION" source="#{id}-pos"/></vertices>
  <triangles count="4" {material}><input semantic="VERTEX" source="#{id}-vtx" offset="0"/>
    <p>0 1 2 0 1 3 0 2 3 1 2 3</p></triangles>
</mesh></geometry>"##,
                p.join(" ")
            )
        };
        let dae = format!(
            r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="mm" meter="0.001"/><up_axis>Z_UP</up_axis></asset>
  <library_effects><effect id="red-fx"><profile_COMMON><technique sid="t"><lambert>
    <diffuse><color>1 0 0 1</color></diffuse></lambert></technique></profile_COMMON></effect>
  </library_effects>
  <library_materials><material id="red" name="red"><instance_effect url="#red-fx"/></material>
  </library_materials>
  <library_geometries>{}{}</library_geometries>
  <library_visual_scenes><visual_scene id="s">
    <node id="a"><instance_geometry url="#a"/></node>
    <node id="b"><instance_geometry url="#b"><bind_material><technique_common>
      <instance_material symbol="m" target="#red"/></technique_common></bind_material>
    </instance_geometry></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##,
            geometry("a", 0.0, ""),
            geometry("b", 10.0, "material=\"m\"")
        );
        let path = tmp.path().join("two.dae");
        std::fs::write(&path, dae).unwrap();
        let mesh = read_mesh_triangles(&path).unwrap();
        assert_eq!(mesh.triangles.len(), 8);
        // Each triangle lies in one part: the first part is at x < 2 mm, the second (10 mm
        // on) beyond; a joined index list that pointed into the wrong part would mix them.
        let x = |i: u32| mesh.vertices[i as usize][0];
        let far = |t: &&[u32; 3]| t.iter().all(|&i| x(i) >= 0.0099);
        let near = |t: &&[u32; 3]| t.iter().all(|&i| x(i) <= 0.0011);
        assert_eq!(mesh.triangles.iter().filter(far).count(), 4);
        assert_eq!(mesh.triangles.iter().filter(near).count(), 4);
        // The unit applies: 11 mm is the far corner.
        assert!((mesh.bounds().unwrap().1[0] - 0.011).abs() < 1e-6);
        assert_eq!(mesh.color, Some([1.0, 0.0, 0.0, 1.0]));
    }

    #[test]
    fn a_binary_stl_whose_header_reads_as_ascii_is_read_as_binary() {
        // "solid foot", spaces, and a count of 13 (0x0D, a carriage return): mesh-loader
        // alone reads a solid named "foot …" and fails on the first triangle's bytes.
        let mut bytes = box_stl_binary([0.1, 0.1, 0.1]);
        let header = format!("{:<80}", "solid foot");
        bytes[..80].copy_from_slice(header.as_bytes());
        bytes[80..84].copy_from_slice(&13u32.to_le_bytes());
        let first = bytes[84..134].to_vec();
        bytes.extend_from_slice(&first);
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("foot.stl");
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(read_mesh_triangles(&path).unwrap().triangles.len(), 13);
        // A broken file of another size still fails.
        bytes.push(0);
        std::fs::write(&path, &bytes).unwrap();
        assert!(read_mesh_triangles(&path).is_err());
    }

    #[test]
    fn what_is_not_a_mesh_is_an_error_naming_the_file() {
        let tmp = tempfile::tempdir().unwrap();
        let junk = tmp.path().join("junk.stl");
        std::fs::write(&junk, [0xFFu8; 10]).unwrap();
        assert!(read_mesh_triangles(&junk)
            .unwrap_err()
            .to_string()
            .contains("junk.stl"));
        let png = tmp.path().join("x.png");
        std::fs::write(&png, b"\x89PNG").unwrap();
        assert!(read_mesh_triangles(&png)
            .unwrap_err()
            .message
            .contains("not a mesh format"));
        assert!(read_mesh_triangles(&tmp.path().join("missing.obj")).is_err());
        let dir = tmp.path().join("dir.stl");
        std::fs::create_dir(&dir).unwrap();
        assert!(read_mesh_triangles(&dir)
            .unwrap_err()
            .message
            .contains("not a regular file"));
    }

    #[test]
    fn a_sphere_simplified_keeps_under_the_cap_and_its_shape() {
        let fine = sphere(0.5, 60, 120);
        assert_eq!(fine.triangles.len(), 14_400);
        for cap in [2000, 500, 100] {
            let coarse = fine.simplified(cap);
            assert!(coarse.triangles.len() <= cap, "{cap}");
            assert!(
                coarse.triangles.len() > cap / 3,
                "{cap}: only {}",
                coarse.triangles.len()
            );
            // Means of points on the sphere lie just inside it.
            let (lo, hi) = radius_range(&coarse);
            assert!(lo > 0.4 && hi <= 0.5001, "{cap}: radii {lo}..{hi}");
            assert!(coarse
                .triangles
                .iter()
                .all(|t| t.iter().all(|&i| (i as usize) < coarse.vertices.len())));
        }
    }

    #[test]
    fn degenerate_meshes_simplify_to_nothing_without_panicking() {
        let point = TriMesh {
            vertices: vec![[1.0, 1.0, 1.0]; 3],
            triangles: vec![[0, 1, 2]],
            color: None,
        };
        assert!(point.simplified(10).triangles.is_empty());
        assert!(TriMesh::default().simplified(10).triangles.is_empty());
        assert!(sphere(1.0, 10, 10).simplified(0).triangles.is_empty());
    }
}
