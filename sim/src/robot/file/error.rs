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
}

impl FileError {
    pub(super) fn new(file: &Path, text: &str, at: Position, message: impl Into<String>) -> Self {
        Self {
            file: file.to_owned(),
            at,
            message: crate::yaml_words::elide_long_tokens(&message.into()),
            source_line: crate::yaml_words::source_line(text, at.line),
        }
    }

    /// The YAML reader's error, in a file author's words ([`crate::yaml_words`]).
    pub(super) fn from_yaml(file: &Path, text: &str, error: &serde_saphyr::Error) -> Self {
        let at = error
            .location()
            .map(|l| Position::from_location(&l))
            .unwrap_or_default();
        Self::new(file, text, at, crate::yaml_words::message(error))
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
