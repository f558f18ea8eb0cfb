//! The JSON configuration file: one object whose values are all strings, in the
//! `ArmFactoryParam` dictionary format.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::error::{AbcErrorCode, ArmError};
use super::params::{ArmFactoryParam, ParamError};

/// Why a configuration file could not be used. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not valid JSON.
    #[error("{}:{line}:{column}: not valid JSON: {reason}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// Line of the error (1-based).
        line: usize,
        /// Column of the error (1-based).
        column: usize,
        /// What was wrong.
        reason: String,
    },
    /// The top level is not a JSON object.
    #[error("{}: the configuration must be a JSON object", path.display())]
    NotAnObject {
        /// The file.
        path: PathBuf,
    },
    /// A value is not a JSON string (the format writes every value as a string).
    #[error("{}: key {key:?} must be a string, got {value}", path.display())]
    NotAString {
        /// The file.
        path: PathBuf,
        /// The key.
        key: String,
        /// The value, as JSON.
        value: String,
    },
    /// The parameters are missing a key or have a malformed value.
    #[error("{}: {source}", path.display())]
    Param {
        /// The file.
        path: PathBuf,
        /// The parameter error.
        source: ParamError,
    },
}

impl ConfigError {
    /// The API code for this error.
    pub fn code(&self) -> AbcErrorCode {
        match self {
            Self::Param { source, .. } => source.code(),
            _ => AbcErrorCode::ParamError,
        }
    }
}

impl From<ConfigError> for ArmError {
    fn from(e: ConfigError) -> Self {
        ArmError::caused_by(e.code(), e)
    }
}

/// Parses configuration text; `path` only labels errors.
pub fn parse_config(text: &str, path: &Path) -> Result<ArmFactoryParam, ConfigError> {
    let path_buf = || path.to_path_buf();
    let value: Value = serde_json::from_str(text).map_err(|e| ConfigError::Json {
        path: path_buf(),
        line: e.line(),
        column: e.column(),
        reason: e.to_string(),
    })?;
    let Value::Object(obj) = value else {
        return Err(ConfigError::NotAnObject { path: path_buf() });
    };
    let mut map = BTreeMap::new();
    for (key, value) in obj {
        match value {
            Value::String(s) => {
                map.insert(key, s);
            }
            other => {
                return Err(ConfigError::NotAString {
                    path: path_buf(),
                    key,
                    value: other.to_string(),
                })
            }
        }
    }
    ArmFactoryParam::from_map(&map).map_err(|source| ConfigError::Param {
        path: path_buf(),
        source,
    })
}

/// Reads and validates the configuration file at `path`.
pub fn load_config(path: impl AsRef<Path>) -> Result<ArmFactoryParam, ConfigError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_config(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::Vendor;

    const SEED_FORMAT: &str = r#"{
        "arm_type": "realman",
        "arm_name": "left_arm",
        "ip": "192.168.1.18",
        "port": "8080",
        "udp_ip": "192.168.1.102",
        "udp_port": "8089",
        "udp_cycle": "1",
        "enable_gripper": "false"
    }"#;

    fn parse(text: &str) -> Result<ArmFactoryParam, ConfigError> {
        parse_config(text, Path::new("arm.json"))
    }

    #[test]
    fn the_documented_format_parses() {
        let p = parse(SEED_FORMAT).unwrap();
        assert_eq!(p.arm_type, Vendor::Realman);
        assert_eq!((p.port, p.udp_port, p.udp_cycle), (8080, 8089, 1));
        assert!(!p.enable_gripper);
    }

    #[test]
    fn a_missing_key_is_named_with_the_file() {
        let text = SEED_FORMAT.replace("\"udp_ip\": \"192.168.1.102\",", "");
        let e = parse(&text).unwrap_err();
        assert_eq!(e.code(), AbcErrorCode::ParamError);
        assert_eq!(e.to_string(), "arm.json: missing key \"udp_ip\"");
    }

    #[test]
    fn a_malformed_value_names_key_and_value() {
        let text = SEED_FORMAT.replace("\"8080\"", "\"80x80\"");
        let e = parse(&text).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("\"port\"") && text.contains("\"80x80\""),
            "{text}"
        );
    }

    #[test]
    fn a_non_string_value_is_refused_with_key_and_value() {
        let text = SEED_FORMAT.replace("\"8080\"", "8080");
        let e = parse(&text).unwrap_err();
        assert!(matches!(e, ConfigError::NotAString { ref key, .. } if key == "port"));
        assert!(e.to_string().contains("got 8080"), "{e}");
    }

    #[test]
    fn bad_json_and_bad_shapes_name_the_file() {
        let e = parse("{\"arm_type\": \"realman\",").unwrap_err();
        assert!(matches!(e, ConfigError::Json { line: 1, .. }), "{e:?}");
        assert!(e.to_string().starts_with("arm.json:1:"), "{e}");
        let e = parse("[1, 2]").unwrap_err();
        assert!(matches!(e, ConfigError::NotAnObject { .. }));
    }

    #[test]
    fn an_unreadable_file_is_named() {
        let e = load_config("/nonexistent/armhil/arm.json").unwrap_err();
        assert!(matches!(e, ConfigError::Read { .. }));
        assert!(
            e.to_string().contains("/nonexistent/armhil/arm.json"),
            "{e}"
        );
        assert_eq!(ArmError::from(e).value(), -50);
    }
}
