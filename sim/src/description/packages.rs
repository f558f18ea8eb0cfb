//! Where a URDF's `package://` and relative file names point, found the way ROS finds them.

use std::path::{Path, PathBuf};

/// Where to look for the files a URDF names (meshes).
///
/// A `package://NAME/rest` URI is looked up, in this order, in the robot file's own
/// `packages:` map, in each folder of `ROS_PACKAGE_PATH` (a folder holding `NAME/package.xml`,
/// searched to a few levels as `rospack` does) and in each prefix of `AMENT_PREFIX_PATH`
/// (`PREFIX/share/NAME`). A relative name is relative to the URDF's folder; `file://` and
/// absolute names are taken as they are.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PackagePaths {
    /// The URDF's folder (relative names start here); `None` for URDF text with no file.
    pub urdf_dir: Option<PathBuf>,
    /// The robot file's `packages:` map: package name → its folder.
    pub packages: Vec<(String, PathBuf)>,
    /// `ROS_PACKAGE_PATH`'s folders.
    pub ros_package_path: Vec<PathBuf>,
    /// `AMENT_PREFIX_PATH`'s prefixes.
    pub ament_prefix_path: Vec<PathBuf>,
}

/// A file a URDF names that is nowhere to be found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{uri}` is not found ({})", searched_list(.uri, .searched))]
pub struct NotFound {
    /// The name as the URDF gives it.
    pub uri: String,
    /// Every place looked at, in order.
    pub searched: Vec<PathBuf>,
}

fn searched_list(uri: &str, searched: &[PathBuf]) -> String {
    if searched.is_empty() {
        return match uri.strip_prefix("package://") {
            Some(rest) => format!(
                "no folder is known for package `{}`: name it in the robot file's `packages:`, or set ROS_PACKAGE_PATH or AMENT_PREFIX_PATH",
                rest.trim_start_matches('/').split('/').next().unwrap_or_default()
            ),
            None => "a relative name, and the URDF has no folder to start from".to_owned(),
        };
    }
    let places: Vec<String> = searched.iter().map(|p| p.display().to_string()).collect();
    format!("looked in: {}", places.join(", "))
}

/// How deep below a `ROS_PACKAGE_PATH` folder a `package.xml` is looked for (rospack
/// crawls the whole tree; a bound keeps a path set to `/` from walking the disk).
const CRAWL_DEPTH: usize = 3;
/// Most folders looked into while crawling one `ROS_PACKAGE_PATH` entry.
const CRAWL_FOLDERS: usize = 10_000;

impl PackagePaths {
    /// Paths for the URDF at `urdf_path`, with `ROS_PACKAGE_PATH` and `AMENT_PREFIX_PATH`
    /// read from the environment and the robot file's `packages` map.
    pub fn for_urdf(urdf_path: &Path, packages: Vec<(String, PathBuf)>) -> Self {
        let split = |var: &str| -> Vec<PathBuf> {
            std::env::var_os(var)
                .map(|v| {
                    std::env::split_paths(&v)
                        .filter(|p| !p.as_os_str().is_empty())
                        .collect()
                })
                .unwrap_or_default()
        };
        Self {
            urdf_dir: Some(
                urdf_path
                    .parent()
                    .map_or_else(|| PathBuf::from("."), Path::to_owned),
            ),
            packages,
            ros_package_path: split("ROS_PACKAGE_PATH"),
            ament_prefix_path: split("AMENT_PREFIX_PATH"),
        }
    }

    /// The file `uri` names, or every place it was looked for.
    pub fn resolve(&self, uri: &str) -> Result<PathBuf, NotFound> {
        let mut searched = Vec::new();
        let found = if let Some(rest) = uri.strip_prefix("package://") {
            // `package:///name/…` (an empty host) is seen in published URDFs; ROS tools read
            // it as `package://name/…`.
            let rest = rest.trim_start_matches('/');
            let (package, inside) = rest.split_once('/').unwrap_or((rest, ""));
            self.package_folders(package, &mut searched)
                .into_iter()
                .map(|folder| folder.join(inside))
                .find(|candidate| {
                    searched.push(candidate.clone());
                    candidate.is_file()
                })
        } else {
            let plain = uri.strip_prefix("file://").unwrap_or(uri);
            let path = Path::new(plain);
            let candidate = match (&self.urdf_dir, path.is_absolute()) {
                (_, true) => Some(path.to_owned()),
                (Some(dir), false) => Some(dir.join(path)),
                (None, false) => None,
            };
            candidate.filter(|c| {
                searched.push(c.clone());
                c.is_file()
            })
        };
        found.ok_or_else(|| NotFound {
            uri: uri.to_owned(),
            searched,
        })
    }

    /// The folders that may be package `name`, in the order they are tried.
    fn package_folders(&self, name: &str, searched: &mut Vec<PathBuf>) -> Vec<PathBuf> {
        let mut folders: Vec<PathBuf> = self
            .packages
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, folder)| folder.clone())
            .collect();
        for root in &self.ros_package_path {
            match find_package_xml(root, name) {
                Some(folder) => folders.push(folder),
                None => searched.push(root.join(name).join("package.xml")),
            }
        }
        for prefix in &self.ament_prefix_path {
            folders.push(prefix.join("share").join(name));
        }
        folders
    }
}

/// The folder below `root` (to [`CRAWL_DEPTH`] levels, `root` included) that holds a
/// `package.xml` and is called `name` (as the ament index names packages) or whose manifest
/// says `<name>name</name>` (as rospack does): published packages disagree with their own
/// manifests often enough that both are taken.
fn find_package_xml(root: &Path, name: &str) -> Option<PathBuf> {
    let mut queue = std::collections::VecDeque::from([(root.to_owned(), 0usize)]);
    let mut visited = 0usize;
    while let Some((folder, depth)) = queue.pop_front() {
        visited += 1;
        if visited > CRAWL_FOLDERS {
            return None;
        }
        let manifest = folder.join("package.xml");
        let folder_is_named = folder.file_name().is_some_and(|n| n == name);
        if manifest.is_file()
            && (folder_is_named || package_name(&manifest).as_deref() == Some(name))
        {
            return Some(folder);
        }
        if depth == CRAWL_DEPTH {
            continue;
        }
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        let mut children: Vec<PathBuf> = entries
            .filter_map(Result::ok)
            .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
            .map(|e| e.path())
            .collect();
        // Deterministic: the same tree gives the same package whatever order the disk lists.
        children.sort();
        queue.extend(children.into_iter().map(|c| (c, depth + 1)));
    }
    None
}

/// The `<name>` of a `package.xml` (at most 256 KiB read: anything larger is no manifest).
fn package_name(manifest: &Path) -> Option<String> {
    let bytes = crate::bounded_read::read_regular_file(manifest, 256 * 1024).ok()?;
    let text = String::from_utf8_lossy(&bytes);
    text.split_once("<name>")
        .and_then(|(_, rest)| rest.split_once("</name>"))
        .map(|(name, _)| name.trim().to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(path: &Path, text: &str) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }

    #[test]
    fn a_package_is_found_by_its_manifest_on_ros_package_path() {
        let tmp = tempfile::tempdir().unwrap();
        // The folder's name differs from the package's: the manifest decides.
        touch(
            &tmp.path().join("src/robots/desc_folder/package.xml"),
            "<package><name>my_robot_description</name></package>",
        );
        touch(
            &tmp.path().join("src/robots/desc_folder/meshes/foot.stl"),
            "solid",
        );
        let paths = PackagePaths {
            ros_package_path: vec![tmp.path().join("src")],
            ..PackagePaths::default()
        };
        let found = paths
            .resolve("package://my_robot_description/meshes/foot.stl")
            .unwrap();
        assert_eq!(
            found,
            tmp.path().join("src/robots/desc_folder/meshes/foot.stl")
        );
        // An empty host, and the folder's own name, find it too.
        touch(
            &tmp.path().join("src/robots/desc_folder/package.xml"),
            "<package/>",
        );
        assert_eq!(
            paths
                .resolve("package:///desc_folder/meshes/foot.stl")
                .unwrap(),
            found
        );
    }

    #[test]
    fn the_robot_files_map_comes_before_the_environment_and_ament_is_share() {
        let tmp = tempfile::tempdir().unwrap();
        touch(&tmp.path().join("mine/m.stl"), "x");
        touch(&tmp.path().join("prefix/share/pkg/m.stl"), "x");
        let mut paths = PackagePaths {
            packages: vec![("pkg".into(), tmp.path().join("mine"))],
            ament_prefix_path: vec![tmp.path().join("prefix")],
            ..PackagePaths::default()
        };
        assert_eq!(
            paths.resolve("package://pkg/m.stl").unwrap(),
            tmp.path().join("mine/m.stl")
        );
        paths.packages.clear();
        assert_eq!(
            paths.resolve("package://pkg/m.stl").unwrap(),
            tmp.path().join("prefix/share/pkg/m.stl")
        );
    }

    #[test]
    fn a_missing_file_lists_every_place_searched() {
        let tmp = tempfile::tempdir().unwrap();
        let paths = PackagePaths {
            urdf_dir: Some(tmp.path().to_owned()),
            packages: vec![("pkg".into(), tmp.path().join("a"))],
            ros_package_path: vec![tmp.path().join("ros")],
            ament_prefix_path: vec![tmp.path().join("ament")],
        };
        let error = paths.resolve("package://pkg/meshes/x.dae").unwrap_err();
        let text = error.to_string();
        assert!(
            text.contains("`package://pkg/meshes/x.dae` is not found"),
            "{text}"
        );
        for place in [
            "a/meshes/x.dae",
            "ros/pkg/package.xml",
            "ament/share/pkg/meshes/x.dae",
        ] {
            assert!(text.contains(place), "{place} missing from: {text}");
        }
        let relative = paths.resolve("meshes/y.stl").unwrap_err();
        assert_eq!(relative.searched, vec![tmp.path().join("meshes/y.stl")]);
    }

    #[test]
    fn relative_and_file_uris_start_at_the_urdf() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(tmp.path().join("urdf")).unwrap();
        touch(&tmp.path().join("meshes/a.obj"), "");
        let paths = PackagePaths::for_urdf(&tmp.path().join("urdf/robot.urdf"), Vec::new());
        assert!(paths.resolve("../meshes/a.obj").is_ok());
        let absolute = format!("file://{}", tmp.path().join("meshes/a.obj").display());
        assert!(paths.resolve(&absolute).is_ok());
    }
}
