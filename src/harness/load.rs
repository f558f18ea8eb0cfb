//! Reading scenario files: both layers, and folder discovery.

use std::path::{Path, PathBuf};

use super::model::Scenario;
use super::raw::{RawBench, RawScenario, S};
use crate::scenario::error::{from_yaml_error, LoadError, Pos, ScenarioError};

/// The bench alone (every other key ignored).
#[derive(serde::Deserialize)]
struct RawHead {
    bench: S<RawBench>,
}
use super::validate::{matrix_shape, validate_with, MatrixShape};
use crate::scenario::read_in::{KindSet, ReadIn};
use crate::scenario::{Ctx, Res};

/// Parse and validate scenario text; `path` is used for error messages and relative URDFs. A
/// file with a `matrix:` is refused here (it is several scenarios): see [`parse_variant`].
pub fn parse_scenario(path: &Path, text: &str) -> Result<Scenario, LoadError> {
    parse_variant(path, text, None)
}

/// Parse and validate the variant `variant` (a value of its `matrix:`) of scenario text;
/// `None` for a file without a matrix.
pub fn parse_variant(
    path: &Path,
    text: &str,
    variant: Option<&str>,
) -> Result<Scenario, LoadError> {
    Parsed::new(path, text.to_owned()).variant(variant)
}

/// A scenario file parsed once (layer 1) with its `matrix:` checked, from which each variant
/// is validated (layer 2) without parsing the file again.
struct Parsed {
    path: PathBuf,
    text: String,
    /// The file as written, or why it does not parse.
    raw: Result<RawScenario, Box<ScenarioError>>,
    /// Its matrix, checked once for all variants.
    shape: Res<Option<MatrixShape>>,
}

impl Parsed {
    fn new(path: &Path, text: String) -> Self {
        // The bench first: its device kinds decide which vocabulary the steps are read with.
        // When it does not parse, the full parse below reports the error.
        let kinds = serde_saphyr::from_str::<RawHead>(&text)
            .map(|head| {
                crate::devices::kinds_named(
                    head.bench
                        .value
                        .devices
                        .value
                        .values()
                        .map(|d| d.value.kind_name()),
                )
            })
            .unwrap_or(KindSet::ALL);
        let raw =
            serde_saphyr::with_deserializer_from_str(&text, |de| RawScenario::read_in(de, kinds))
                .map_err(|error| Box::new(from_yaml_error(path, &text, &error)));
        let shape = match &raw {
            Ok(raw) => matrix_shape(&Ctx::new(path, &text), raw.matrix.as_ref()),
            Err(_) => Ok(None),
        };
        Self {
            path: path.to_path_buf(),
            text,
            raw,
            shape,
        }
    }

    /// Validate the variant `variant` (`None`: the file has no matrix).
    fn variant(&self, variant: Option<&str>) -> Result<Scenario, LoadError> {
        let raw = self
            .raw
            .as_ref()
            .map_err(|e| LoadError::Invalid(e.clone()))?;
        let mut ctx = Ctx::new(&self.path, &self.text).for_variant(variant);
        validate_with(&mut ctx, raw, &self.shape).map_err(LoadError::Invalid)
    }
}

/// Loads the entries of a suite, reading and parsing each file once however many `matrix:`
/// variants it has: the last file parsed is kept, and a file's variants are consecutive in
/// [`discover_suite`]'s order. (Reading and parsing the whole file again per variant made
/// `armhil check` quadratic in the size of a matrix: 23 s for a 17 KB file.)
#[derive(Default)]
pub struct SuiteLoader {
    last: Option<Parsed>,
    parses: usize,
}

impl std::fmt::Debug for SuiteLoader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SuiteLoader")
            .field("last", &self.last.as_ref().map(|p| &p.path))
            .field("parses", &self.parses)
            .finish()
    }
}

impl SuiteLoader {
    /// A loader that has parsed nothing yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Read (unless it is the file of the previous entry), parse and validate the scenario of
    /// `file` (its matrix variant, if any).
    pub fn load(&mut self, file: &SuiteFile) -> Result<Scenario, LoadError> {
        let parsed = match self.last.take() {
            Some(p) if p.path == file.path => p,
            _ => {
                let text = read_text(&file.path)?;
                self.parses += 1;
                Parsed::new(&file.path, text)
            }
        };
        let scenario = parsed.variant(file.variant.as_deref());
        self.last = Some(parsed);
        scenario
    }

    /// How many files this loader has read and parsed.
    pub fn parses(&self) -> usize {
        self.parses
    }
}

/// Read, parse and validate a scenario of a suite (its matrix variant, if any). To load many
/// entries, a [`SuiteLoader`] parses each file once.
pub fn load_suite_file(file: &SuiteFile) -> Result<Scenario, LoadError> {
    SuiteLoader::new().load(file)
}

/// Largest scenario file read, bytes: 16 MiB. The scenarios in this repository are a few KB
/// (the longest a few dozen); 16 MiB is a thousand times that, still parses in seconds and
/// fits in any machine's memory, while `/dev/zero`, a pipe that never ends or a mistyped path
/// to a multi-GB log is refused after 16 MiB instead of being read whole (9 GB and rising
/// before this bound).
pub const MAX_SCENARIO_BYTES: u64 = 16 * 1024 * 1024;

/// The bytes of `path`, at most [`MAX_SCENARIO_BYTES`] of them. Only a regular file is read
/// (a device such as `/dev/zero` never ends, a pipe blocks or is consumed by the first of the
/// two reads a suite makes), and one over the limit is refused by its size before reading; the
/// read itself stops at the limit too, in case the file grows meanwhile.
fn read_bounded(path: &Path) -> Result<Vec<u8>, LoadError> {
    use sim::bounded_read::{read_regular_file, BoundedReadError};
    let path_buf = path.to_path_buf();
    read_regular_file(path, MAX_SCENARIO_BYTES).map_err(|error| match error {
        BoundedReadError::NotAFile => LoadError::NotAFile { path: path_buf },
        BoundedReadError::TooLarge { limit_bytes } => LoadError::TooLarge {
            path: path_buf,
            limit_bytes,
        },
        BoundedReadError::Io(source) => LoadError::Io {
            path: path_buf,
            source,
        },
    })
}

/// The `matrix:` of a file alone (every other key ignored).
#[derive(serde::Deserialize)]
struct RawMatrixHead {
    matrix: Option<std::collections::BTreeMap<String, Vec<String>>>,
}

/// The values of a file's one-parameter `matrix:`; `None` when it has none or it does not
/// read (loading the file then reports why).
fn matrix_values(path: &Path) -> Option<Vec<String>> {
    let text = String::from_utf8(read_bounded(path).ok()?).ok()?;
    let head: RawMatrixHead = serde_saphyr::from_str(&text).ok()?;
    let matrix = head.matrix?;
    let mut entries = matrix.into_values();
    match (entries.next(), entries.next()) {
        (Some(values), None) if !values.is_empty() => Some(values),
        _ => None,
    }
}

/// Read, parse and validate one scenario file.
pub fn load_scenario(path: &Path) -> Result<Scenario, LoadError> {
    let text = read_text(path)?;
    parse_scenario(path, &text)
}

/// A scenario file's text; text that is not UTF-8 is an error at the line and column of its
/// first bad byte (UTF-16, recognised by its byte-order mark, gets a hint to re-save).
fn read_text(path: &Path) -> Result<String, LoadError> {
    let bytes = read_bounded(path)?;
    String::from_utf8(bytes).map_err(|error| {
        let bytes = error.as_bytes();
        let message = if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
            "the file is UTF-16; save it as UTF-8".to_owned()
        } else {
            let at = error.utf8_error().valid_up_to();
            format!("not valid UTF-8 (byte offset {at}); save the file as UTF-8")
        };
        LoadError::Invalid(Box::new(ScenarioError::new(
            path,
            utf8_pos(bytes, error.utf8_error().valid_up_to()),
            message,
        )))
    })
}

/// Line and column (in characters) of byte `at` of `bytes`, whose first `at` bytes are UTF-8.
fn utf8_pos(bytes: &[u8], at: usize) -> Pos {
    let before = String::from_utf8_lossy(&bytes[..at]);
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    Pos {
        line: before.matches('\n').count() as u64 + 1,
        column: before[line_start..].chars().count() as u64 + 1,
    }
}

/// A scenario of a suite and the folder its outputs go to, relative to the output root: its
/// path under the folder it was found in, without extension (`piper/move_l` for
/// `scenarios/piper/move_l.yaml` found under `scenarios/`), or its stem for a file named
/// directly. Two files never share a folder unless they were named as the same path. A file
/// with `matrix: {vendor: [piper, realman]}` is one entry per value, each with a subfolder
/// (`arm/moves/piper`, `arm/moves/realman`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SuiteFile {
    /// The scenario file.
    pub path: PathBuf,
    /// Output folder relative to the output root.
    pub out_dir: PathBuf,
    /// The matrix value this entry runs (`None`: the file has no matrix).
    pub variant: Option<String>,
}

impl SuiteFile {
    /// One entry per matrix value of `path` (one entry without variant when it has none).
    fn expand(path: PathBuf, out_dir: PathBuf) -> Vec<SuiteFile> {
        match matrix_values(&path) {
            Some(values) => values
                .into_iter()
                .map(|v| SuiteFile {
                    path: path.clone(),
                    out_dir: out_dir.join(&v),
                    variant: Some(v),
                })
                .collect(),
            None => vec![SuiteFile {
                path,
                out_dir,
                variant: None,
            }],
        }
    }
}

/// Like [`discover`], with each file's output folder.
pub fn discover_suite(paths: &[PathBuf]) -> Result<Vec<SuiteFile>, LoadError> {
    let mut found = Vec::new();
    for root in paths {
        if root.is_dir() {
            let mut files = Vec::new();
            walk(root, &mut files)?;
            for path in files {
                let rel = path.strip_prefix(root).unwrap_or(&path).with_extension("");
                found.extend(SuiteFile::expand(path, rel));
            }
        } else {
            let stem = root.file_stem().map_or_else(
                || PathBuf::from("scenario"),
                |s| PathBuf::from(s.to_os_string()),
            );
            found.extend(SuiteFile::expand(root.clone(), stem));
        }
    }
    Ok(found)
}

/// Expand files and folders into the scenario files they hold (`*.yaml`, `*.yml`, searched
/// recursively, sorted by path so suites run in a stable order).
pub fn discover(paths: &[PathBuf]) -> Result<Vec<PathBuf>, LoadError> {
    let mut found = Vec::new();
    for path in paths {
        if path.is_dir() {
            walk(path, &mut found)?;
        } else {
            found.push(path.clone());
        }
    }
    Ok(found)
}

/// Every `*.yaml` / `*.yml` under `dir`, sorted by path. Symbolic links to folders are
/// followed, but each real folder is searched once: a link back into a folder being searched
/// (a loop, which used to be followed 40 levels deep until the OS gave up) is an error naming
/// the link, and a second link to a folder already searched is skipped.
fn walk(dir: &Path, found: &mut Vec<PathBuf>) -> Result<(), LoadError> {
    let mut searching = Vec::new();
    let mut searched = std::collections::BTreeSet::new();
    walk_in(dir, found, &mut searching, &mut searched)
}

/// [`walk`] with the real paths of the folders being searched (the current chain) and of every
/// folder searched so far.
fn walk_in(
    dir: &Path,
    found: &mut Vec<PathBuf>,
    searching: &mut Vec<PathBuf>,
    searched: &mut std::collections::BTreeSet<PathBuf>,
) -> Result<(), LoadError> {
    let io = |source| LoadError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let real = std::fs::canonicalize(dir).map_err(io)?;
    if searching.contains(&real) {
        return Err(LoadError::SymlinkLoop {
            link: dir.to_path_buf(),
            target: real,
        });
    }
    if !searched.insert(real.clone()) {
        tracing::warn!(
            folder = %dir.display(),
            real = %real.display(),
            "folder already searched through another path; its scenarios are not run twice"
        );
        return Ok(());
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    entries.sort();
    searching.push(real);
    for entry in entries {
        if entry.is_dir() {
            walk_in(&entry, found, searching, searched)?;
        } else if matches!(
            entry.extension().and_then(|e| e.to_str()),
            Some("yaml" | "yml")
        ) {
            found.push(entry);
        }
    }
    searching.pop();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_file_over_the_limit_is_refused_by_its_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("huge.yaml");
        // Sparse: no 17 MiB is written, but the size says it.
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(MAX_SCENARIO_BYTES + 1).unwrap();
        let err = load_scenario(&path).unwrap_err();
        assert!(matches!(err, LoadError::TooLarge { .. }), "{err}");
        let text = err.to_string();
        assert!(text.starts_with(&format!("{}: ", path.display())), "{text}");
        assert!(text.contains("16 MiB"), "{text}");
    }

    #[cfg(unix)]
    #[test]
    fn a_device_is_not_read_at_all() {
        let path = Path::new("/dev/zero");
        let err = load_scenario(path).unwrap_err();
        assert!(matches!(err, LoadError::NotAFile { .. }), "{err}");
        assert_eq!(
            err.to_string(),
            "/dev/zero: not a regular file (a device, pipe or folder), so not read as a scenario"
        );
        // The matrix probe of suite discovery reads the same way.
        assert_eq!(matrix_values(path), None);
        let err = check_one(&[PathBuf::from("/dev/zero")]);
        assert!(err.contains("/dev/zero: not a regular file"), "{err}");
    }

    /// The first load error of a suite of `paths`.
    fn check_one(paths: &[PathBuf]) -> String {
        let entries = discover_suite(paths).unwrap();
        let mut loader = SuiteLoader::new();
        loader.load(&entries[0]).unwrap_err().to_string()
    }

    #[test]
    fn a_large_matrix_is_parsed_once_for_all_its_variants() {
        const N: usize = 3000;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("wide.yaml");
        let values: Vec<String> = (0..N).map(|i| format!("v{i}")).collect();
        let text = format!(
            "matrix: {{n: [{}]}}\nbench:\n  devices:\n    arm: {{kind: piper}}\nsteps:\n  - wait_ms: 1\n",
            values.join(", ")
        );
        std::fs::write(&path, text).unwrap();
        let entries = discover_suite(std::slice::from_ref(&path)).unwrap();
        assert_eq!(entries.len(), N);
        let mut loader = SuiteLoader::new();
        for (entry, value) in entries.iter().zip(&values) {
            let scenario = loader.load(entry).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(scenario.variant.as_deref(), Some(value.as_str()));
        }
        // Each variant is validated from the one parse: the work per variant does not grow
        // with the matrix (reading the file again per variant made `check` quadratic).
        assert_eq!(loader.parses(), 1);
        // A second file is parsed once more, and going back to the first parses it again.
        let other = dir.path().join("plain.yaml");
        std::fs::write(
            &other,
            "bench:\n  devices:\n    arm: {kind: piper}\nsteps:\n  - wait_ms: 1\n",
        )
        .unwrap();
        let plain = discover_suite(std::slice::from_ref(&other)).unwrap();
        loader.load(&plain[0]).unwrap();
        loader.load(&entries[7]).unwrap();
        assert_eq!(loader.parses(), 3);
    }

    #[test]
    fn matrix_errors_are_the_same_through_the_loader() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("dup.yaml");
        std::fs::write(
            &path,
            "matrix: {n: [a, b, a]}\nbench:\n  devices:\n    arm: {kind: piper}\nsteps:\n  - wait_ms: 1\n",
        )
        .unwrap();
        let entries = discover_suite(std::slice::from_ref(&path)).unwrap();
        let mut loader = SuiteLoader::new();
        for entry in &entries {
            let err = loader.load(entry).unwrap_err().to_string();
            assert!(err.contains("dup.yaml:1:20: `a` is listed twice"), "{err}");
        }
        let missing = SuiteFile {
            path: path.clone(),
            out_dir: PathBuf::from("dup/c"),
            variant: Some("c".to_owned()),
        };
        assert!(loader.load(&missing).is_err());
        assert_eq!(loader.parses(), 1);
    }

    #[test]
    fn a_small_file_is_read_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.yaml");
        std::fs::write(&path, b"#").unwrap();
        assert_eq!(read_bounded(&path).unwrap(), b"#");
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_loop_is_an_error_naming_the_link() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("scenarios");
        std::fs::create_dir_all(root.join("piper")).unwrap();
        std::fs::write(root.join("piper/a.yaml"), "").unwrap();
        std::os::unix::fs::symlink("..", root.join("piper/up")).unwrap();
        let err = discover(std::slice::from_ref(&root)).unwrap_err();
        let LoadError::SymlinkLoop { link, .. } = &err else {
            panic!("{err}");
        };
        assert_eq!(link, &root.join("piper/up"));
        assert!(err.to_string().contains("symbolic link loop"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_folder_linked_twice_is_searched_once() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("scenarios");
        std::fs::create_dir_all(root.join("real")).unwrap();
        std::fs::write(root.join("real/a.yaml"), "").unwrap();
        std::os::unix::fs::symlink("real", root.join("alias")).unwrap();
        let found = discover(std::slice::from_ref(&root)).unwrap();
        // `alias` sorts first, so the file is found through it, and only once.
        assert_eq!(found, vec![root.join("alias/a.yaml")]);
    }
}
