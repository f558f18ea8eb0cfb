//! Reading scenario files: both layers, and folder discovery.

use std::path::{Path, PathBuf};

use super::error::{from_yaml_error, LoadError, Pos, ScenarioError};
use super::model::Scenario;
use super::raw::{RawBench, RawScenario, S};

/// The bench alone (every other key ignored).
#[derive(serde::Deserialize)]
struct RawHead {
    bench: S<RawBench>,
}
use super::validate::{validate, Ctx};

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
    // The bench first: its device kinds decide which vocabulary the steps are read with. When
    // it does not parse, the full parse below reports the error.
    let kinds = serde_saphyr::from_str::<RawHead>(text).ok().map(|head| {
        head.bench
            .value
            .devices
            .value
            .values()
            .map(|d| d.value.kind_name())
            .collect::<Vec<_>>()
    });
    let parse = || serde_saphyr::from_str::<RawScenario>(text);
    let raw = match kinds {
        Some(kinds) => crate::devices::with_bench_kinds(kinds, parse),
        None => parse(),
    }
    .map_err(|error| LoadError::Invalid(Box::new(from_yaml_error(path, text, &error))))?;
    let mut ctx = Ctx::new(path, text).for_variant(variant);
    validate(&mut ctx, raw).map_err(LoadError::Invalid)
}

/// Read, parse and validate a scenario of a suite (its matrix variant, if any).
pub fn load_suite_file(file: &SuiteFile) -> Result<Scenario, LoadError> {
    let text = read_text(&file.path)?;
    parse_variant(&file.path, &text, file.variant.as_deref())
}

/// The `matrix:` of a file alone (every other key ignored).
#[derive(serde::Deserialize)]
struct RawMatrixHead {
    matrix: Option<std::collections::BTreeMap<String, Vec<String>>>,
}

/// The values of a file's one-parameter `matrix:`; `None` when it has none or it does not
/// read (loading the file then reports why).
fn matrix_values(path: &Path) -> Option<Vec<String>> {
    let text = std::fs::read_to_string(path).ok()?;
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
    let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
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

fn walk(dir: &Path, found: &mut Vec<PathBuf>) -> Result<(), LoadError> {
    let io = |source| LoadError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    entries.sort();
    for entry in entries {
        if entry.is_dir() {
            walk(&entry, found)?;
        } else if matches!(
            entry.extension().and_then(|e| e.to_str()),
            Some("yaml" | "yml")
        ) {
            found.push(entry);
        }
    }
    Ok(())
}
