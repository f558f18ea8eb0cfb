//! Errors of loading a scenario: every one names the file, line and column.

use std::fmt;
use std::path::{Path, PathBuf};

/// A position in a scenario file (1-based line and column; 0 when unknown).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Pos {
    /// 1-based line.
    pub line: u64,
    /// 1-based column.
    pub column: u64,
}

impl Pos {
    /// A position from serde-saphyr's location.
    pub(crate) fn from_location(location: &serde_saphyr::Location) -> Self {
        Self {
            line: location.line(),
            column: location.column(),
        }
    }
}

/// `text` with every over-long token cut short, so a huge bad value is not echoed whole (the
/// same rule for every file error the project reports).
pub use sim::yaml_words::elide_long_tokens;

/// One problem in a scenario file, with where it is and what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScenarioError {
    /// The file the problem is in.
    pub file: PathBuf,
    /// Where in the file.
    pub pos: Pos,
    /// What is wrong and what was expected.
    pub message: String,
    /// The offending source line, for display under the message.
    pub source_line: Option<String>,
}

impl ScenarioError {
    /// A problem at `pos` in `file`.
    pub fn new(file: &Path, pos: Pos, message: impl Into<String>) -> Self {
        Self {
            file: file.to_path_buf(),
            pos,
            message: elide_long_tokens(&message.into()),
            source_line: None,
        }
    }

    /// Attach the source line the position points into, for display. A line too long to read
    /// on a terminal is left out: the headline already says where the problem is.
    pub(crate) fn with_source(mut self, text: &str) -> Self {
        self.source_line = sim::yaml_words::source_line(text, self.pos.line);
        self
    }

    /// `file:line:col: message`, without the source excerpt.
    pub fn headline(&self) -> String {
        format!(
            "{}:{}:{}: {}",
            self.file.display(),
            self.pos.line,
            self.pos.column,
            self.message
        )
    }
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.headline())?;
        if let Some(line) = &self.source_line {
            let gutter = self.pos.line.to_string();
            let pad = " ".repeat(gutter.len());
            let caret_pad =
                " ".repeat(usize::try_from(self.pos.column.saturating_sub(1)).unwrap_or(0));
            write!(f, "\n{pad} |\n{gutter} | {line}\n{pad} | {caret_pad}^")?;
        }
        Ok(())
    }
}

impl std::error::Error for ScenarioError {}

/// Why a scenario could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file holds more than the limit (a regular file by its size; a device or pipe once
    /// that much was read from it).
    #[error(
        "{}: larger than {} MiB, the limit for a scenario file (is it one?)",
        path.display(),
        limit_bytes / (1024 * 1024)
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit, bytes.
        limit_bytes: u64,
    },
    /// Not a regular file: a device (`/dev/zero` never ends), a pipe or a folder.
    #[error(
        "{}: not a regular file (a device, pipe or folder), so not read as a scenario",
        path.display()
    )]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// Scenario folders lead back into themselves through a symbolic link.
    #[error(
        "{}: symbolic link loop: it leads back to {}, which is already being searched",
        link.display(),
        target.display()
    )]
    SymlinkLoop {
        /// The link (as found while searching).
        link: PathBuf,
        /// The folder it resolves to.
        target: PathBuf,
    },
    /// The file was read but is not a valid scenario.
    #[error("{0}")]
    Invalid(#[from] Box<ScenarioError>),
}

impl LoadError {
    /// The scenario error, when the file was readable.
    pub fn scenario_error(&self) -> Option<&ScenarioError> {
        match self {
            Self::Invalid(error) => Some(error),
            Self::Io { .. }
            | Self::TooLarge { .. }
            | Self::NotAFile { .. }
            | Self::SymlinkLoop { .. } => None,
        }
    }
}

/// Turn a serde-saphyr error into a [`ScenarioError`] with a friendlier message.
pub(crate) fn from_yaml_error(
    file: &Path,
    text: &str,
    error: &serde_saphyr::Error,
) -> ScenarioError {
    let pos = error
        .location()
        .map(|location| Pos::from_location(&location))
        .unwrap_or_default();
    ScenarioError::new(file, pos, sim::yaml_words::message(error)).with_source(text)
}

/// `; did you mean `x`?` when one of `candidates` is within two edits of `word`, else empty
/// (every file the project reads says it the same way).
pub(crate) use sim::yaml_words::suggestion;
