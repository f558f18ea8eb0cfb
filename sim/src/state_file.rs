//! What the emulators' state files (their "flash") have in common: a header naming the
//! emulator the file belongs to (`kind`) and the version of its layout (`format`), checked
//! before anything else in the file is read, and the atomic write.
//!
//! The header exists so that a file is never read as something it is not: a Piper file given
//! to the Realman emulator, or a file of a later layout, is refused with an error that names
//! the file and the field instead of being half-read into defaults. Each emulator then checks
//! every value with the same rules its set commands apply (a value the firmware would refuse
//! over the wire is refused in the file too), so a hand-edited file cannot put the emulator
//! into a state no command could reach (D4: min above max panicked the core at the first move).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// The layout version this build reads and writes.
pub const FORMAT: u32 = 1;

/// A value a state file (or a configuration) holds that the firmware's commands would refuse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("field `{field}`: {problem}")]
pub struct InvalidField {
    /// Where the value is, as a path into the file (`flash.min_angle_ddeg[2]`).
    pub field: String,
    /// Why it is refused.
    pub problem: String,
}

impl InvalidField {
    /// The value at `field` is refused because of `problem`.
    pub fn new(field: impl Into<String>, problem: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            problem: problem.into(),
        }
    }
}

/// Why a state file could not be read, checked or written. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum StateFileError {
    /// Reading or writing failed.
    #[error("state file {path}: {action}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The step that failed ("reading", "writing the temporary file", "renaming the
        /// temporary file over it", ...).
        action: &'static str,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not JSON of the expected layout (a wrong type, an unknown field).
    #[error("state file {path}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A field holds a value the emulator refuses (the header included).
    #[error("state file {path}: {invalid}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The field and why.
        #[source]
        invalid: InvalidField,
    },
}

impl StateFileError {
    /// `invalid` found in the file at `path`.
    pub fn invalid(path: &Path, invalid: InvalidField) -> Self {
        Self::Invalid {
            path: path.to_owned(),
            invalid,
        }
    }

    fn io(path: &Path, action: &'static str, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            action,
            source,
        }
    }

    fn syntax(path: &Path, error: &serde_json::Error) -> Self {
        Self::Syntax {
            path: path.to_owned(),
            line: error.line(),
            column: error.column(),
            message: error.to_string(),
        }
    }
}

/// The two fields every state file starts with; anything else is ignored at this stage.
#[derive(Deserialize)]
struct Header {
    kind: Option<serde_json::Value>,
    format: Option<serde_json::Value>,
}

/// Check that `text` (the file at `path`) is a state file of emulator `kind` in [`FORMAT`].
fn check_header(path: &Path, text: &str, kind: &str) -> Result<(), StateFileError> {
    let header: Header =
        serde_json::from_str(text).map_err(|e| StateFileError::syntax(path, &e))?;
    let refuse = |field: &str, problem: String| {
        Err(StateFileError::invalid(
            path,
            InvalidField::new(field, problem),
        ))
    };
    match header.kind {
        Some(serde_json::Value::String(found)) if found == kind => {}
        Some(serde_json::Value::String(found)) => {
            return refuse(
                "kind",
                format!("the file belongs to the {found:?} emulator, not to {kind:?}"),
            )
        }
        Some(other) => return refuse("kind", format!("{other} is not an emulator name")),
        None => {
            return refuse(
                "kind",
                format!(
                    "missing: not an armhil state file, or one from before state files named \
                     their emulator (expected \"kind\": {kind:?}, \"format\": {FORMAT}; delete \
                     the file to start from the defaults)"
                ),
            )
        }
    }
    match header.format {
        Some(serde_json::Value::Number(n)) if n.as_u64() == Some(u64::from(FORMAT)) => Ok(()),
        Some(other) => refuse(
            "format",
            format!("{other} is not a format this build reads (it reads {FORMAT})"),
        ),
        None => refuse("format", format!("missing (expected {FORMAT})")),
    }
}

/// Largest state file read, bytes: 16 MiB. A state file holds a few kilobytes (a bus of 127
/// motors ~100 KB); the bound stops a mistyped path to `/dev/zero` or a huge file from being
/// read whole into memory.
pub const MAX_STATE_FILE_BYTES: u64 = 16 * 1024 * 1024;

/// Read the state file at `path` as a `T` (the whole document, header fields included) after
/// checking its header is `kind` / [`FORMAT`]. `Ok(None)` if the file does not exist (the
/// device's first power-on). The caller then checks the values.
pub fn load<T: DeserializeOwned>(path: &Path, kind: &str) -> Result<Option<T>, StateFileError> {
    use crate::bounded_read::{read_regular_file, BoundedReadError};
    let refuse = |why: String| {
        StateFileError::io(
            path,
            "reading",
            std::io::Error::new(std::io::ErrorKind::InvalidData, why),
        )
    };
    let bytes = match read_regular_file(path, MAX_STATE_FILE_BYTES) {
        Ok(bytes) => bytes,
        Err(BoundedReadError::Io(e)) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(None)
        }
        Err(BoundedReadError::Io(e)) => return Err(StateFileError::io(path, "reading", e)),
        Err(BoundedReadError::NotAFile) => return Err(refuse("not a regular file".to_owned())),
        Err(BoundedReadError::TooLarge { limit_bytes }) => {
            return Err(refuse(format!(
                "larger than {} MiB, the limit for a state file (one holds a few kilobytes)",
                limit_bytes >> 20
            )))
        }
    };
    let text = String::from_utf8(bytes).map_err(|_| refuse("not UTF-8 text".to_owned()))?;
    check_header(path, &text, kind)?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| StateFileError::syntax(path, &e))
}

/// Write `document` to `path` so that the file is always complete: a temporary file beside it,
/// written and synced, renamed over `path`, then the folder synced (the rename itself reaches
/// the disk). On an error the temporary file is removed and `path` is left as it was.
///
/// This is the one way every emulator saves its state file; the bytes are the document as
/// pretty JSON and a final newline.
pub fn save<T: Serialize>(path: &Path, document: &T) -> Result<(), StateFileError> {
    let text = serde_json::to_string_pretty(document)
        .map_err(|e| StateFileError::io(path, "encoding", std::io::Error::other(e)))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let failed = |action| move |e| StateFileError::io(path, action, e);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".armhil-state-");
    // A temporary file is private (0600) by default; a state file is an ordinary file whose
    // mode the umask decides, as `File::create` would make it.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(failed("creating a temporary file beside it"))?;
    tmp.write_all(text.as_bytes())
        .and_then(|()| tmp.write_all(b"\n"))
        .map_err(failed("writing the temporary file"))?;
    tmp.as_file()
        .sync_all()
        .map_err(failed("syncing the temporary file"))?;
    tmp.persist(path)
        .map_err(|e| failed("renaming the temporary file over it")(e.error))?;
    // Best effort: some file systems refuse to open or sync a folder.
    #[cfg(unix)]
    if let Ok(folder) = std::fs::File::open(dir) {
        let _ = folder.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Doc {
        kind: String,
        format: u32,
        value: u8,
    }

    fn doc(value: u8) -> Doc {
        Doc {
            kind: "test".into(),
            format: FORMAT,
            value,
        }
    }

    fn invalid_field(result: Result<Option<Doc>, StateFileError>) -> String {
        match result {
            Err(StateFileError::Invalid { invalid, .. }) => invalid.field,
            other => panic!("expected an invalid field, got {other:?}"),
        }
    }

    #[test]
    fn a_saved_file_reads_back_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        save(&path, &doc(7)).unwrap();
        save(&path, &doc(8)).unwrap();
        assert_eq!(load::<Doc>(&path, "test").unwrap(), Some(doc(8)));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        assert_eq!(
            load::<Doc>(&dir.path().join("none.json"), "test").unwrap(),
            None
        );
    }

    #[test]
    fn another_kind_another_format_or_no_header_is_refused_naming_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        save(&path, &doc(1)).unwrap();
        let err = load::<Doc>(&path, "realman").unwrap_err().to_string();
        assert!(
            err.contains("s.json") && err.contains("`kind`") && err.contains("\"test\""),
            "{err}"
        );
        std::fs::write(&path, r#"{"kind":"test","format":2,"value":1}"#).unwrap();
        assert_eq!(invalid_field(load(&path, "test")), "format");
        std::fs::write(&path, r#"{"format":1,"value":1}"#).unwrap();
        assert_eq!(invalid_field(load(&path, "test")), "kind");
        std::fs::write(&path, r#"{"kind":"test","value":1}"#).unwrap();
        assert_eq!(invalid_field(load(&path, "test")), "format");
        std::fs::write(&path, "{\"kind\":\"test\",\"format\":1,\n\"other\":1}").unwrap();
        match load::<Doc>(&path, "test") {
            Err(StateFileError::Syntax { line: 2, .. }) => {}
            other => panic!("an unknown field must be refused with its line: {other:?}"),
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_device_a_folder_or_a_huge_file_is_refused_without_reading_it() {
        let dir = tempfile::tempdir().unwrap();
        let huge = dir.path().join("huge.json");
        // Sparse: no disk used, and `load` must refuse it by its size without reading.
        std::fs::File::create(&huge)
            .unwrap()
            .set_len(MAX_STATE_FILE_BYTES + 1)
            .unwrap();
        let named = |path: &Path, why: &str| {
            let err = load::<Doc>(path, "test").unwrap_err().to_string();
            let name = path.display().to_string();
            assert!(err.contains(&name) && err.contains(why), "{err}");
        };
        named(&huge, "larger than 16 MiB, the limit for a state file");
        named(Path::new("/dev/zero"), "not a regular file");
        named(dir.path(), "not a regular file");
        std::fs::write(&huge, [b'{', 0xFF, b'}']).unwrap();
        named(&huge, "not UTF-8");
    }

    #[cfg(unix)]
    #[test]
    fn a_file_that_cannot_be_written_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gone").join("s.json");
        let err = save(&path, &doc(1)).unwrap_err();
        assert!(
            matches!(err, StateFileError::Io { .. }) && err.to_string().contains("gone"),
            "{err}"
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_save_refused_at_the_rename_leaves_no_temporary_file_and_names_the_step() {
        let dir = tempfile::tempdir().unwrap();
        // The target is a folder: the temporary file is written, the rename over it fails.
        let path = dir.path().join("taken");
        std::fs::create_dir(&path).unwrap();
        let err = save(&path, &doc(1)).unwrap_err();
        let message = err.to_string();
        assert!(
            matches!(err, StateFileError::Io { action, .. } if action.starts_with("renaming"))
                && message.contains(&path.display().to_string()),
            "{message}"
        );
        assert!(path.is_dir(), "the folder must be left as it was");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn a_save_into_a_read_only_folder_leaves_the_old_file_whole() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        save(&path, &doc(1)).unwrap();
        let before = std::fs::read(&path).unwrap();
        std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o555)).unwrap();
        let result = save(&path, &doc(2));
        std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
        if result.is_ok() {
            // Running as root, which ignores the folder's mode: nothing to check here.
            return;
        }
        let err = result.unwrap_err();
        assert!(
            matches!(err, StateFileError::Io { action, .. } if action.starts_with("creating"))
                && err.to_string().contains(&path.display().to_string()),
            "{err}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), before);
        assert_eq!(load::<Doc>(&path, "test").unwrap(), Some(doc(1)));
    }

    #[cfg(unix)]
    #[test]
    fn a_saved_file_is_pretty_json_with_a_final_newline_and_the_umask_mode() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        save(&path, &doc(3)).unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "{\n  \"kind\": \"test\",\n  \"format\": 1,\n  \"value\": 3\n}\n"
        );
        // Compared with a file made the ordinary way, so the test holds under any umask.
        let plain = dir.path().join("plain");
        std::fs::write(&plain, b"").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&plain));
    }
}
