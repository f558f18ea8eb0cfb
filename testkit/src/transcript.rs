//! The reader for JSON test-vector transcripts (`fixtures/realman/*.jsonl`).
//!
//! The Realman driver and the Realman emulator each have their own codec; they share only these
//! transcripts. This module is the one place that reads them, so both sides agree on the format
//! (described in `fixtures/realman/README.md`): one JSON object per line, `#` comments, fields
//! `name`, `request`, `replies`, `compare`, `notes`, and the optional `channel` and `profile`.
//!
//! [`matches()`] implements the two comparison modes so an emulator test and a driver test judge a
//! reply the same way.

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use serde_json::Value;
use thiserror::Error;

/// How a reply produced by an implementation is compared with the vector's reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compare {
    /// Same JSON value (key order and whitespace do not matter).
    #[default]
    Exact,
    /// Same tag, same keys at every level, same JSON types; values are not compared.
    Shape,
}

/// Where a vector's replies travel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Channel {
    /// The TCP command connection (CRLF-terminated lines).
    #[default]
    Tcp,
    /// The UDP state push (one datagram per reply, no terminator).
    Udp,
}

/// One test vector: a request and what the controller answers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Vector {
    /// Unique name within its file.
    pub name: String,
    /// Exact wire text the client sends, CRLF included; empty for unsolicited traffic.
    pub request: String,
    /// Wire text of each reply or event, in order.
    pub replies: Vec<String>,
    /// How replies are compared.
    pub compare: Compare,
    /// Free text: units, preconditions.
    pub notes: String,
    /// Transport of the replies.
    pub channel: Channel,
    /// Situation the vector applies to (`None` = the default controller).
    pub profile: Option<String>,
    /// 1-based line number in the file, for messages.
    pub line: usize,
}

/// The raw line as serde sees it; converted into [`Vector`] with the line number added.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVector {
    name: String,
    request: String,
    replies: Vec<String>,
    #[serde(default)]
    compare: Compare,
    #[serde(default)]
    notes: String,
    #[serde(default)]
    channel: Channel,
    #[serde(default)]
    profile: Option<String>,
}

/// The vectors of one file, in file order.
#[derive(Debug, Clone)]
pub struct Transcript {
    /// Where the vectors came from (a path or a label given to [`Transcript::parse`]).
    pub origin: String,
    /// The vectors in file order.
    pub vectors: Vec<Vector>,
}

/// Why a transcript could not be read. Every variant names the file and, where there is one,
/// the line.
#[derive(Debug, Error)]
pub enum TranscriptError {
    /// The file or directory could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The path that failed.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A line is not a valid vector.
    #[error("{origin}:{line}: {message}")]
    Parse {
        /// File name or label.
        origin: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Two vectors in one file share a name.
    #[error("{origin}:{line}: duplicate vector name {name:?} (first on line {first_line})")]
    DuplicateName {
        /// File name or label.
        origin: String,
        /// 1-based line of the second occurrence.
        line: usize,
        /// The repeated name.
        name: String,
        /// 1-based line of the first occurrence.
        first_line: usize,
    },
    /// A vector looked up by name does not exist.
    #[error("{origin}: no vector named {name:?}")]
    Missing {
        /// File name or label.
        origin: String,
        /// The name asked for.
        name: String,
    },
}

impl Transcript {
    /// Reads and parses one `.jsonl` file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, TranscriptError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| TranscriptError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses transcript text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Self, TranscriptError> {
        let mut vectors = Vec::new();
        let mut seen: HashMap<String, usize> = HashMap::new();
        for (index, raw_line) in text.lines().enumerate() {
            let line = index + 1;
            let trimmed = raw_line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let raw: RawVector =
                serde_json::from_str(trimmed).map_err(|e| TranscriptError::Parse {
                    origin: origin.to_string(),
                    line,
                    message: e.to_string(),
                })?;
            validate(&raw).map_err(|message| TranscriptError::Parse {
                origin: origin.to_string(),
                line,
                message,
            })?;
            if let Some(&first_line) = seen.get(&raw.name) {
                return Err(TranscriptError::DuplicateName {
                    origin: origin.to_string(),
                    line,
                    name: raw.name,
                    first_line,
                });
            }
            seen.insert(raw.name.clone(), line);
            vectors.push(Vector {
                name: raw.name,
                request: raw.request,
                replies: raw.replies,
                compare: raw.compare,
                notes: raw.notes,
                channel: raw.channel,
                profile: raw.profile,
                line,
            });
        }
        Ok(Self {
            origin: origin.to_string(),
            vectors,
        })
    }

    /// The vector called `name`.
    pub fn get(&self, name: &str) -> Result<&Vector, TranscriptError> {
        self.vectors
            .iter()
            .find(|v| v.name == name)
            .ok_or_else(|| TranscriptError::Missing {
                origin: self.origin.clone(),
                name: name.to_string(),
            })
    }
}

/// Checks what serde cannot: non-empty names and replies that are themselves JSON objects.
fn validate(raw: &RawVector) -> Result<(), String> {
    if raw.name.is_empty() {
        return Err("empty vector name".into());
    }
    for (i, reply) in raw.replies.iter().enumerate() {
        match serde_json::from_str::<Value>(reply.trim_end()) {
            Ok(Value::Object(_)) => {}
            Ok(_) => return Err(format!("reply {i} is not a JSON object")),
            Err(e) => return Err(format!("reply {i} is not JSON: {e}")),
        }
        if raw.channel == Channel::Tcp && !reply.ends_with("\r\n") {
            return Err(format!("TCP reply {i} does not end in CRLF"));
        }
    }
    Ok(())
}

/// The directory holding the Realman transcripts in this repository.
pub fn realman_fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/realman")
}

/// Loads every `*.jsonl` file in `dir`, sorted by file name.
pub fn load_dir(dir: impl AsRef<Path>) -> Result<Vec<Transcript>, TranscriptError> {
    let dir = dir.as_ref();
    let io = |source| TranscriptError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    paths.sort();
    paths.into_iter().map(Transcript::load).collect()
}

/// Why a reply does not match a vector's reply.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mismatch {
    /// JSON-pointer-like path of the first difference (`/arm_state/err`).
    pub path: String,
    /// What differs.
    pub reason: String,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "at {}: {}", self.path, self.reason)
    }
}

/// Compares an `actual` reply (wire text) with an `expected` one under `mode`.
pub fn matches(mode: Compare, expected: &str, actual: &str) -> Result<(), Mismatch> {
    let parse = |text: &str, which: &str| {
        serde_json::from_str::<Value>(text.trim_end()).map_err(|e| Mismatch {
            path: String::new(),
            reason: format!("{which} is not JSON: {e}"),
        })
    };
    let expected = parse(expected, "expected")?;
    let actual = parse(actual, "actual")?;
    match mode {
        Compare::Exact if expected == actual => Ok(()),
        Compare::Exact => Err(Mismatch {
            path: String::new(),
            reason: format!("expected {expected}, got {actual}"),
        }),
        Compare::Shape => {
            // The tag says which reply this is, so it must match even in shape mode.
            for tag in ["state", "command"] {
                if expected.get(tag) != actual.get(tag) {
                    return Err(Mismatch {
                        path: format!("/{tag}"),
                        reason: format!("tag {:?} vs {:?}", expected.get(tag), actual.get(tag)),
                    });
                }
            }
            shape(&expected, &actual, "")
        }
    }
}

/// Same keys at every level and the same JSON type for every value.
fn shape(expected: &Value, actual: &Value, path: &str) -> Result<(), Mismatch> {
    let mismatch = |reason: String| Mismatch {
        path: if path.is_empty() {
            "/".into()
        } else {
            path.into()
        },
        reason,
    };
    match (expected, actual) {
        (Value::Object(e), Value::Object(a)) => {
            let missing: Vec<_> = e.keys().filter(|k| !a.contains_key(*k)).collect();
            let extra: Vec<_> = a.keys().filter(|k| !e.contains_key(*k)).collect();
            if !missing.is_empty() || !extra.is_empty() {
                return Err(mismatch(format!(
                    "missing keys {missing:?}, extra keys {extra:?}"
                )));
            }
            e.iter()
                .try_for_each(|(k, ev)| shape(ev, &a[k], &format!("{path}/{k}")))
        }
        (Value::Array(e), Value::Array(a)) => e
            .iter()
            .zip(a)
            .enumerate()
            .filter(|(_, (ev, _))| ev.is_object())
            .try_for_each(|(i, (ev, av))| shape(ev, av, &format!("{path}/{i}"))),
        (e, a) if type_name(e) == type_name(a) => Ok(()),
        (e, a) => Err(mismatch(format!(
            "type {} vs {}",
            type_name(e),
            type_name(a)
        ))),
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "bool",
        Value::Number(_) => "number",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = concat!(
        "# comment\n",
        "\n",
        r#"{"name":"a","request":"{\"command\":\"x\"}\r\n","replies":["{\"state\":\"y\",\"v\":[1,2]}\r\n"],"notes":"n"}"#,
        "\n",
        r#"{"name":"b","request":"","replies":["{\"state\":\"u\"}"],"compare":"shape","channel":"udp","profile":"legacy_err"}"#,
        "\n"
    );

    #[test]
    fn parses_fields_defaults_and_line_numbers() {
        let t = Transcript::parse(GOOD, "good.jsonl").unwrap();
        assert_eq!(t.vectors.len(), 2);
        let a = t.get("a").unwrap();
        assert_eq!(a.line, 3);
        assert_eq!(a.request, "{\"command\":\"x\"}\r\n");
        assert_eq!(a.compare, Compare::Exact);
        assert_eq!(a.channel, Channel::Tcp);
        let b = t.get("b").unwrap();
        assert_eq!(
            (b.line, b.compare, b.channel),
            (4, Compare::Shape, Channel::Udp)
        );
        assert_eq!(b.profile.as_deref(), Some("legacy_err"));
        assert!(matches!(t.get("c"), Err(TranscriptError::Missing { .. })));
    }

    #[test]
    fn errors_name_file_and_line() {
        let text = format!("{GOOD}{{\"name\":\"c\",\"request\":\"\"}}\n");
        let err = Transcript::parse(&text, "bad.jsonl").unwrap_err();
        assert!(err.to_string().starts_with("bad.jsonl:5: "), "{err}");
        let dup = format!("{GOOD}{}\n", GOOD.lines().nth(2).unwrap());
        let err = Transcript::parse(&dup, "dup.jsonl").unwrap_err();
        assert!(
            matches!(
                err,
                TranscriptError::DuplicateName {
                    line: 5,
                    first_line: 3,
                    ..
                }
            ),
            "{err}"
        );
        let no_crlf = r#"{"name":"d","request":"","replies":["{\"state\":\"y\"}"]}"#;
        let err = Transcript::parse(no_crlf, "crlf.jsonl").unwrap_err();
        assert!(
            err.to_string().contains("crlf.jsonl:1: TCP reply 0"),
            "{err}"
        );
        let unknown_field = r#"{"name":"d","request":"","replies":[],"colour":1}"#;
        assert!(Transcript::parse(unknown_field, "f").is_err());
    }

    #[test]
    fn exact_and_shape_comparison() {
        let e = r#"{"state":"s","a":{"b":[1,2]},"c":"x"}"#;
        assert!(super::matches(
            Compare::Exact,
            e,
            r#"{"c":"x","a":{"b":[1,2]},"state":"s"}"#
        )
        .is_ok());
        assert!(super::matches(
            Compare::Exact,
            e,
            r#"{"state":"s","a":{"b":[1,3]},"c":"x"}"#
        )
        .is_err());
        assert!(super::matches(Compare::Shape, e, r#"{"state":"s","a":{"b":[]},"c":"y"}"#).is_ok());
        let err =
            super::matches(Compare::Shape, e, r#"{"state":"s","a":{"b":1},"c":"x"}"#).unwrap_err();
        assert_eq!(err.path, "/a/b");
        assert!(
            super::matches(Compare::Shape, e, r#"{"state":"t","a":{"b":[]},"c":"y"}"#).is_err()
        );
        assert!(super::matches(Compare::Shape, e, r#"{"state":"s","a":{"b":[]}}"#).is_err());
    }

    #[test]
    fn repository_fixtures_load() {
        let all = load_dir(realman_fixtures_dir()).unwrap();
        assert!(all.len() >= 7, "{} files", all.len());
        for t in &all {
            assert!(!t.vectors.is_empty(), "{} is empty", t.origin);
        }
    }
}
