//! A problem at a place in a robot file.

use std::fmt;
use std::path::{Path, PathBuf};

/// 1-based line and column in a file (0 when unknown).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Position {
    /// 1-based line.
    pub line: u64,
    /// 1-based column.
    pub column: u64,
}

impl Position {
    /// Where a YAML value starts.
    pub(super) fn of<T>(value: &serde_saphyr::Spanned<T>) -> Self {
        Self::from_location(&value.referenced)
    }

    pub(super) fn from_location(location: &serde_saphyr::Location) -> Self {
        Self {
            line: location.line(),
            column: location.column(),
        }
    }
}

/// One problem in a robot file: where, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileError {
    /// The file.
    pub file: PathBuf,
    /// Where in it.
    pub at: Position,
    /// What is wrong and what was expected.
    pub message: String,
    /// The line `at` points into, for display under the message.
    pub source_line: Option<String>,
    /// Whether the YAML reader found it (its words, which a caller may rephrase), rather than
    /// the robot file's own checks.
    pub from_yaml_reader: bool,
}

impl FileError {
    pub(super) fn new(file: &Path, text: &str, at: Position, message: impl Into<String>) -> Self {
        let line = usize::try_from(at.line.saturating_sub(1)).unwrap_or(usize::MAX);
        Self {
            file: file.to_owned(),
            at,
            message: message.into(),
            source_line: (at.line > 0)
                .then(|| text.lines().nth(line).map(str::to_owned))
                .flatten(),
            from_yaml_reader: false,
        }
    }

    /// The YAML reader's error, without the position its message repeats.
    pub(super) fn from_yaml(file: &Path, text: &str, error: &serde_saphyr::Error) -> Self {
        let at = error
            .location()
            .map(|l| Position::from_location(&l))
            .unwrap_or_default();
        let raw = error.without_snippet().to_string();
        let message = match raw.rfind(" at line ") {
            Some(cut) => raw[..cut].to_owned(),
            None => raw,
        };
        Self {
            from_yaml_reader: true,
            ..Self::new(file, text, at, message)
        }
    }
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file.display(),
            self.at.line,
            self.at.column,
            self.message
        )
    }
}

impl std::error::Error for FileError {}

/// `; did you mean `x`?` when one of `candidates` is within two edits of `word`, else empty.
pub fn suggestion(word: &str, candidates: &[&str]) -> String {
    candidates
        .iter()
        .map(|c| (strsim::levenshtein(word, c), *c))
        .filter(|(d, c)| *d <= 2 && *d < c.len())
        .min()
        .map_or_else(String::new, |(_, c)| format!("; did you mean `{c}`?"))
}
