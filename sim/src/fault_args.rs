//! The arguments of a named emulator fault as a front end read them, and why they were refused.
//!
//! Every emulator has one fault builder (`FaultKind::build` in its `faults` module), driven by
//! its fault table (names, parameters, ranges, defaults). The scenario files, the web view's
//! JSON and the Python emulators' keyword arguments are three front ends of that builder: each
//! turns what it read into [`FaultArgs`], calls the builder, and shows a [`FaultArgError`] in its
//! own way (a scenario error at the argument's line and column, an HTTP 400 body, a Python
//! `ValueError`) with the same message.

use std::fmt;

/// One argument value as written: every front end reads numbers (YAML, JSON and Python ints and
/// floats alike) and words (a joint or phase name). Serialized as the bare number or word.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum FaultArgValue {
    /// A number.
    Number(f64),
    /// A word.
    Text(String),
}

impl fmt::Display for FaultArgValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Number(v) => write!(f, "{v}"),
            Self::Text(t) => write!(f, "`{t}`"),
        }
    }
}

/// The named arguments of one fault, in the order the front end read them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultArgs {
    entries: Vec<(String, FaultArgValue)>,
}

impl FaultArgs {
    /// No arguments.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add argument `name` (a front end adds each key it read, unknown ones too: the builder
    /// refuses those by name).
    pub fn with(mut self, name: impl Into<String>, value: FaultArgValue) -> Self {
        self.entries.push((name.into(), value));
        self
    }

    /// Add argument `name` in place.
    pub fn push(&mut self, name: impl Into<String>, value: FaultArgValue) {
        self.entries.push((name.into(), value));
    }

    /// The value of `name`, if given.
    pub fn get(&self, name: &str) -> Option<&FaultArgValue> {
        self.entries.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// Every argument, in order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &FaultArgValue)> {
        self.entries.iter().map(|(n, v)| (n.as_str(), v))
    }

    /// `Err` naming the first argument not in `known` (the fault's parameters).
    pub fn only(&self, fault: &str, known: &[&str]) -> Result<(), FaultArgError> {
        match self
            .entries
            .iter()
            .find(|(n, _)| !known.contains(&n.as_str()))
        {
            None => Ok(()),
            Some((name, _)) => Err(FaultArgError::at(
                name,
                if known.is_empty() {
                    format!("fault `{fault}` takes no arguments, got `{name}`")
                } else {
                    format!(
                        "fault `{fault}` has no argument `{name}`; it takes: {}",
                        known.join(", ")
                    )
                },
            )),
        }
    }
}

/// Why a fault could not be built: the message every front end shows, and the argument it is
/// about (`None`: the fault as a whole, e.g. its name or a missing argument), so that a
/// scenario error can point at that argument's line and column.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct FaultArgError {
    /// The argument the message is about, if one.
    pub arg: Option<String>,
    /// What is wrong, in words a user can act on.
    pub message: String,
}

impl FaultArgError {
    /// An error about argument `arg`.
    pub fn at(arg: &str, message: impl Into<String>) -> Self {
        Self {
            arg: Some(arg.to_owned()),
            message: message.into(),
        }
    }

    /// An error about the fault as a whole.
    pub fn whole(message: impl Into<String>) -> Self {
        Self {
            arg: None,
            message: message.into(),
        }
    }

    /// Fault `fault` was given without its required argument `arg`: an error about the fault
    /// as a whole (the argument has no place in the file to point at).
    pub fn missing(fault: &str, arg: &str) -> Self {
        Self::whole(format!("`{fault}` needs `{arg}`"))
    }
}

/// Longest word a message repeats whole; a longer one (a pasted blob) is cut, so a message
/// stays one readable line.
const SHOWN_WORD_CHARS: usize = 24;

/// `text` in backquotes as a message repeats it: cut after 24 characters, with its length.
pub fn shown_word(text: &str) -> String {
    let count = text.chars().count();
    if count <= SHOWN_WORD_CHARS {
        format!("`{text}`")
    } else {
        let head: String = text.chars().take(SHOWN_WORD_CHARS).collect();
        format!("`{head}…` ({count} characters)")
    }
}

/// The entry of `table` called `name`, or the error every front end shows for an unknown
/// fault: `no <device> fault `name`; known: …` with the table's names in order.
pub fn named<T: Copy>(
    device: &str,
    name: &str,
    table: &[T],
    name_of: impl Fn(T) -> &'static str,
) -> Result<T, FaultArgError> {
    table
        .iter()
        .copied()
        .find(|entry| name_of(*entry) == name)
        .ok_or_else(|| {
            let known: Vec<&str> = table.iter().map(|entry| name_of(*entry)).collect();
            FaultArgError::whole(format!(
                "no {device} fault {}; known: {}",
                shown_word(name),
                known.join(", ")
            ))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_names_the_first_unknown_argument() {
        let args = FaultArgs::new()
            .with("joint", FaultArgValue::Number(2.0))
            .with("volts", FaultArgValue::Number(1.0));
        let err = args.only("joint_error", &["joint", "code"]).unwrap_err();
        assert_eq!(err.arg.as_deref(), Some("volts"));
        assert!(err.message.contains("joint, code"), "{}", err.message);
        let none = FaultArgs::new().with("x", FaultArgValue::Text("a".into()));
        assert!(none
            .only("e_stop", &[])
            .unwrap_err()
            .message
            .contains("takes no arguments"));
        assert!(args.only("joint_error", &["joint", "volts"]).is_ok());
    }
}
