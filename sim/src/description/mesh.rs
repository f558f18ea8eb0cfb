//! Reading the meshes a URDF names (STL binary and ASCII, OBJ, COLLADA) into points, through
//! the bounded reader, once per file.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{Point3, Vector3};

use crate::bounded_read::{read_regular_file, BoundedReadError};

/// Largest mesh file read (bytes): 64 MiB. Public robots' meshes are at most a few MB;
/// the bound keeps a mistyped path to a device or a huge scan from being read whole.
pub const MAX_MESH_BYTES: u64 = 64 * 1024 * 1024;

/// Why a mesh could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mesh {}: {message}", path.display())]
pub struct MeshError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub message: String,
}

/// The vertices of one mesh file in its own frame and unit (metres for STL and OBJ, which
/// carry no unit; COLLADA's `<unit meter>` applied). COLLADA's `<up_axis>` is not: RViz and
/// Gazebo ignore it, and public robots' meshes are drawn for them (87 of one public corpus's
/// 286 COLLADA files say `Y_UP` and are meant Z-up).
pub type MeshPoints = Arc<Vec<Point3<f64>>>;

/// Meshes read so far, by file: a robot whose four feet name one STL reads it once.
#[derive(Debug, Default)]
pub struct MeshCache {
    read: HashMap<PathBuf, MeshPoints>,
}

impl MeshCache {
    /// The vertices of the mesh at `path`, read on first use.
    pub fn points(&mut self, path: &Path) -> Result<MeshPoints, MeshError> {
        if let Some(points) = self.read.get(path) {
            return Ok(points.clone());
        }
        let points = Arc::new(read_mesh_points(path)?);
        self.read.insert(path.to_owned(), points.clone());
        Ok(points)
    }
}

/// mesh-loader's file reader (it asks for an OBJ's `.mtl` files itself): bounded like the
/// mesh. A plain `fn` because mesh-loader takes a function pointer.
fn bounded_reader(path: &Path) -> std::io::Result<Vec<u8>> {
    read_regular_file(path, MAX_MESH_BYTES).map_err(|e| match e {
        BoundedReadError::Io(e) => e,
        BoundedReadError::NotAFile => {
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file")
        }
        BoundedReadError::TooLarge { .. } => std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "larger than 64 MiB, the limit for a mesh file",
        ),
    })
}

/// The scene of the mesh file at `path` as mesh-loader reads it (format from its content and
/// extension), its parts kept apart: the one way the physics and the views open a mesh.
pub(crate) fn load_scene(path: &Path) -> Result<mesh_loader::Scene, MeshError> {
    let fail = |message: String| MeshError {
        path: path.to_owned(),
        message,
    };
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !matches!(extension.as_str(), "stl" | "obj" | "dae") {
        return Err(fail(format!(
            "`.{extension}` is not a mesh format armhil reads (STL, OBJ, COLLADA .dae)"
        )));
    }
    let bytes = bounded_reader(path).map_err(|e| fail(e.to_string()))?;
    let bytes = binary_stl_without_solid(bytes, &extension);
    let loader = mesh_loader::Loader::with_custom_reader(bounded_reader);
    // mesh-loader parses untrusted bytes; a panic in it must not take the emulator down.
    std::panic::catch_unwind(|| loader.load_from_slice(&bytes, path))
        .map_err(|_| fail("the mesh reader failed on this file".to_owned()))?
        .map_err(|e| fail(e.to_string()))
}

/// Reads every vertex of the mesh file at `path`.
pub fn read_mesh_points(path: &Path) -> Result<Vec<Point3<f64>>, MeshError> {
    let fail = |message: String| MeshError {
        path: path.to_owned(),
        message,
    };
    let scene = load_scene(path)?;
    let mut points = Vec::new();
    for mesh in &scene.meshes {
        for v in &mesh.vertices {
            let v = Vector3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
            if !v.iter().all(|c| c.is_finite()) {
                return Err(fail("a vertex is not a finite number".to_owned()));
            }
            points.push(Point3::from(v));
        }
    }
    if points.is_empty() {
        return Err(fail("no vertices".to_owned()));
    }
    Ok(points)
}

/// A binary STL whose 80-byte header starts with `solid` (CAD exporters write that) is read
/// as ASCII by mesh-loader when a byte of its triangle count happens to be a line end; its
/// size gives it away as binary (84 + 50 bytes a triangle), and a blanked first byte makes
/// the reader see it so.
fn binary_stl_without_solid(mut bytes: Vec<u8>, extension: &str) -> Vec<u8> {
    if extension == "stl" && bytes.len() >= 84 && bytes.starts_with(b"solid") {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
        if bytes.len() as u64 == 84 + 50 * u64::from(count) {
            bytes[0] = b' ';
        }
    }
    bytes
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An ASCII STL of an axis-aligned box of half extents `h` centred at the origin.
    pub(crate) fn box_stl_ascii(h: [f64; 3]) -> String {
        let mut text = String::from("solid box\n");
        let c = |i: usize, s: f64| s * h[i];
        // Two triangles per face, written without normals (readers recompute them).
        let faces: [[[f64; 3]; 4]; 6] = [
            [
                [-1., -1., -1.],
                [1., -1., -1.],
                [1., 1., -1.],
                [-1., 1., -1.],
            ],
            [[-1., -1., 1.], [1., -1., 1.], [1., 1., 1.], [-1., 1., 1.]],
            [
                [-1., -1., -1.],
                [1., -1., -1.],
                [1., -1., 1.],
                [-1., -1., 1.],
            ],
            [[-1., 1., -1.], [1., 1., -1.], [1., 1., 1.], [-1., 1., 1.]],
            [
                [-1., -1., -1.],
                [-1., 1., -1.],
                [-1., 1., 1.],
                [-1., -1., 1.],
            ],
            [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
        ];
        for f in faces {
            for tri in [[0, 1, 2], [0, 2, 3]] {
                text.push_str("facet normal 0 0 0\nouter loop\n");
                for k in tri {
                    let p = f[k];
                    text.push_str(&format!(
                        "vertex {} {} {}\n",
                        c(0, p[0]),
                        c(1, p[1]),
                        c(2, p[2])
                    ));
                }
                text.push_str("endloop\nendfacet\n");
            }
        }
        text.push_str("endsolid box\n");
        text
    }

    /// The same box as a binary STL.
    pub(crate) fn box_stl_binary(h: [f64; 3]) -> Vec<u8> {
        let ascii = box_stl_ascii(h);
        let vertices: Vec<[f32; 3]> = ascii
            .lines()
            .filter_map(|l| l.strip_prefix("vertex "))
            .map(|l| {
                let v: Vec<f32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        // Exporters often start a binary header with "solid" too; the size tells them apart.
        let mut bytes = b"solid exported by a CAD tool".to_vec();
        bytes.resize(80, b' ');
        bytes.extend_from_slice(&((vertices.len() / 3) as u32).to_le_bytes());
        for tri in vertices.chunks(3) {
            bytes.extend_from_slice(&[0u8; 12]);
            for v in tri {
                for c in v {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
            bytes.extend_from_slice(&[0u8; 2]);
        }
        bytes
    }

    fn extent(points: &[Point3<f64>]) -> [f64; 6] {
        let mut e = [
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
            -f64::INFINITY,
            -f64::INFINITY,
            -f64::INFINITY,
        ];
        for p in points {
            for i in 0..3 {
                e[i] = e[i].min(p[i]);
                e[i + 3] = e[i + 3].max(p[i]);
            }
        }
        e.map(|v| (v * 1e4).round() / 1e4)
    }

    #[test]
    fn ascii_and_binary_stl_read_the_same_box() {
        let tmp = tempfile::tempdir().unwrap();
        let ascii = tmp.path().join("a.stl");
        let binary = tmp.path().join("b.STL");
        std::fs::write(&ascii, box_stl_ascii([0.1, 0.2, 0.3])).unwrap();
        std::fs::write(&binary, box_stl_binary([0.1, 0.2, 0.3])).unwrap();
        // A triangle count whose low byte is a carriage return, after a `solid` header.
        let tricky = tmp.path().join("c.stl");
        let mut bytes = box_stl_binary([0.1, 0.2, 0.3]);
        let triangles = bytes[84..].to_vec();
        let count = 0x0d_u32 + 256;
        bytes.truncate(80);
        bytes.extend_from_slice(&count.to_le_bytes());
        for k in 0..count as usize {
            let t = k % 12;
            bytes.extend_from_slice(&triangles[t * 50..t * 50 + 50]);
        }
        std::fs::write(&tricky, bytes).unwrap();
        for path in [ascii, binary, tricky] {
            let points = read_mesh_points(&path).unwrap();
            assert_eq!(
                extent(&points),
                [-0.1, -0.2, -0.3, 0.1, 0.2, 0.3],
                "{path:?}"
            );
        }
    }

    #[test]
    fn obj_reads_its_vertices() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("t.obj");
        std::fs::write(
            &path,
            "v 0 0 0\nv 1 0 0\nv 0 2 0\nv 0 0 3\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
        )
        .unwrap();
        assert_eq!(
            extent(&read_mesh_points(&path).unwrap()),
            [0., 0., 0., 1., 2., 3.]
        );
    }

    fn collada(unit_m: f64, up: &str) -> String {
        format!(
            r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="u" meter="{unit_m}"/><up_axis>{up}</up_axis></asset>
  <library_geometries>
    <geometry id="g" name="g"><mesh>
      <source id="g-pos"><float_array id="g-pos-array" count="12">0 0 0 1 0 0 0 2 0 0 0 3</float_array>
        <technique_common><accessor source="#g-pos-array" count="4" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="g-vtx"><input semantic="POSITION" source="#g-pos"/></vertices>
      <triangles count="4"><input semantic="VERTEX" source="#g-vtx" offset="0"/>
        <p>0 1 2 0 1 3 0 2 3 1 2 3</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##
        )
    }

    #[test]
    fn collada_applies_its_unit_and_ignores_its_up_axis_as_rviz_does() {
        let tmp = tempfile::tempdir().unwrap();
        let z_up = tmp.path().join("z.dae");
        std::fs::write(&z_up, collada(0.001, "Z_UP")).unwrap();
        assert_eq!(
            extent(&read_mesh_points(&z_up).unwrap()),
            [0., 0., 0., 0.001, 0.002, 0.003]
        );
        let y_up = tmp.path().join("y.dae");
        std::fs::write(&y_up, collada(1.0, "Y_UP")).unwrap();
        assert_eq!(
            extent(&read_mesh_points(&y_up).unwrap()),
            [0., 0., 0., 1., 2., 3.]
        );
    }

    #[test]
    fn what_is_not_a_mesh_is_an_error_naming_the_file() {
        let tmp = tempfile::tempdir().unwrap();
        let junk = tmp.path().join("junk.stl");
        std::fs::write(&junk, [0xFFu8; 10]).unwrap();
        let e = read_mesh_points(&junk).unwrap_err();
        assert!(e.to_string().contains("junk.stl"), "{e}");
        let png = tmp.path().join("x.png");
        std::fs::write(&png, b"\x89PNG").unwrap();
        let e = read_mesh_points(&png).unwrap_err();
        assert!(e.message.contains("not a mesh format"), "{e}");
        let folder = tmp.path().join("folder.stl");
        std::fs::create_dir(&folder).unwrap();
        let e = read_mesh_points(&folder).unwrap_err();
        assert!(e.message.contains("not a regular file"), "{e}");
    }

    #[test]
    fn the_cache_reads_a_file_once() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("a.stl");
        std::fs::write(&path, box_stl_ascii([0.1, 0.1, 0.1])).unwrap();
        let mut cache = MeshCache::default();
        let first = cache.points(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let again = cache.points(&path).unwrap();
        assert!(Arc::ptr_eq(&first, &again));
    }
}
