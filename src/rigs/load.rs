//! Reading a rig file into one `armhil sim KIND` option list per device.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use sim::bounded_read::read_text_file;

use crate::scenario::error::{from_yaml_error, suggestion};
use crate::scenario::{pos, Pos, ScenarioError, S};

/// Largest rig file read (bytes); a rig of dozens of devices is a few KB.
const MAX_RIG_FILE_BYTES: u64 = 1024 * 1024;
/// Most devices one rig serves: each is an emulator with its own tasks, sockets and
/// physics, and one process on a developer's machine should not be asked for more.
pub const MAX_DEVICES: usize = 64;
/// Longest device name (it appears in every message about the device).
const MAX_NAME_CHARS: usize = 64;

/// An `armhil sim` subcommand a rig can hold: the CLI's registry of served kinds lists them
/// (this reader knows none by name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimKind {
    /// The subcommand's name (`kind:` in the file).
    pub name: &'static str,
    /// The keys written as positional arguments rather than options (`file:` of a robot).
    pub positional_keys: &'static [&'static str],
    /// The keys whose value is a file the device writes (`record`, `state_file`), with `_`
    /// between words: no two devices of a rig may write one file, nor one device two of
    /// its outputs to one file.
    pub output_keys: &'static [&'static str],
}

impl SimKind {
    /// The subcommand's name (`kind:` in the file).
    pub fn name(self) -> &'static str {
        self.name
    }
}

/// A rig file that loaded.
#[derive(Debug, Clone)]
pub struct RigFile {
    /// The file.
    pub file: PathBuf,
    /// Every device, by name (the order they start and stop in).
    pub devices: Vec<RigDevice>,
}

impl RigFile {
    /// The folder relative paths in the file are resolved against.
    pub fn dir(&self) -> &Path {
        self.file.parent().unwrap_or(Path::new("."))
    }
}

/// One device of a rig: its `armhil sim KIND` command line.
#[derive(Debug, Clone)]
pub struct RigDevice {
    /// Its name in the file.
    pub name: String,
    /// Which emulator.
    pub kind: SimKind,
    /// The options and arguments after `armhil sim KIND`, as the command line would have them
    /// (`--iface=can0`, `--`, `robots/humanoid.yaml`).
    pub args: Vec<String>,
    /// Its entry's place in the file, with the line to show (the message is the error's).
    entry: ScenarioError,
}

impl RigDevice {
    /// A problem with this device, at its entry in the rig file.
    pub fn error(&self, message: impl std::fmt::Display) -> ScenarioError {
        let mut error = ScenarioError::new(
            &self.entry.file,
            self.entry.pos,
            format!("device `{}` ({}): {message}", self.name, self.kind.name()),
        );
        error.source_line = self.entry.source_line.clone();
        error
    }
}

/// Why a rig file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum RigFileError {
    /// The file could not be read (missing, not a regular file, too large).
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The file was read but is not a valid rig file.
    #[error("{0}")]
    Invalid(#[from] Box<ScenarioError>),
}

/// One device entry as written: key → value (`kind` among them).
type Entry = BTreeMap<String, S<RawValue>>;

/// The whole file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRig {
    /// Device name → its entry.
    devices: S<BTreeMap<String, S<Entry>>>,
}

/// One option's value: a flag, a number, a word, or a list (the option given once per item).
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawValue {
    Flag(bool),
    Integer(i64),
    Number(f64),
    Text(String),
    List(Vec<RawItem>),
}

/// One item of a list value.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawItem {
    Integer(i64),
    Number(f64),
    Text(String),
}

impl RawItem {
    fn text(&self) -> String {
        match self {
            Self::Integer(i) => i.to_string(),
            Self::Number(x) => x.to_string(),
            Self::Text(t) => t.clone(),
        }
    }
}

/// Loads the rig file `path`: every device's kind and option list, every problem named at
/// its line. Whether the options themselves are right is the command's to say (the CLI
/// parses them and reports through [`RigDevice::error`]).
///
/// `kinds` are the subcommands a device may be, in the order messages list them.
pub fn load_rig_file(path: &Path, kinds: &[SimKind]) -> Result<RigFile, RigFileError> {
    let text = read_text_file(path, MAX_RIG_FILE_BYTES, "rig file").map_err(|message| {
        RigFileError::Read {
            path: path.to_owned(),
            message,
        }
    })?;
    let raw: RawRig = serde_saphyr::from_str(&text).map_err(|e| {
        let mut error = from_yaml_error(path, &text, &e);
        if error.message.contains("untagged enum") {
            // serde's words for "none of the value shapes fit".
            error.message = "an option's value is a word, a number, true/false or a list of \
                             words and numbers (quote a word YAML reads as something else, \
                             such as `y` or `no`)"
                .into();
        }
        Box::new(error)
    })?;
    let err = |at: Pos, message: String| {
        Box::new(ScenarioError::new(path, at, message).with_source(&text))
    };
    if raw.devices.value.is_empty() {
        return Err(err(pos(&raw.devices), "a rig needs at least one device".into()).into());
    }
    if raw.devices.value.len() > MAX_DEVICES {
        return Err(err(
            pos(&raw.devices),
            format!(
                "{} devices; one rig serves at most {MAX_DEVICES}",
                raw.devices.value.len()
            ),
        )
        .into());
    }
    let mut devices = Vec::with_capacity(raw.devices.value.len());
    let mut outputs = Vec::new();
    for (name, entry) in &raw.devices.value {
        let at = pos(entry);
        check_name(name).map_err(|message| err(at, message))?;
        let device_err = |at: Pos, message: String| err(at, format!("device `{name}`: {message}"));
        let kind = kind_of(kinds, &entry.value, at).map_err(|(at, m)| device_err(at, m))?;
        let args = command_line(kind, &entry.value).map_err(|(at, m)| device_err(at, m))?;
        outputs.extend(outputs_of(name, kind, &entry.value, path));
        devices.push(RigDevice {
            name: name.clone(),
            kind,
            args,
            entry: ScenarioError::new(path, at, "").with_source(&text),
        });
    }
    if let Some((at, message)) = shared_output(outputs) {
        return Err(err(at, message).into());
    }
    Ok(RigFile {
        file: path.to_owned(),
        devices,
    })
}

/// A file a device writes, as its entry names it.
#[derive(Debug)]
struct Output<'a> {
    /// Where the value is.
    at: Pos,
    /// The device.
    device: &'a str,
    /// The key, with `_` between words (`state_file`).
    key: String,
    /// The value as written.
    written: String,
    /// The path resolved against the rig file's folder and normalised (shown in messages).
    shown: PathBuf,
    /// What two names of one file have in common (see [`same_file_key`]).
    same: PathBuf,
}

/// The files an entry names for its kind's outputs, resolved against the folder of the rig
/// file `rig` (as the CLI resolves them). A list of one item is that item; a longer one is
/// left to the kind's parser, which takes such an option once only; `true`/`false` name no
/// file.
fn outputs_of<'a>(device: &'a str, kind: SimKind, entry: &Entry, rig: &Path) -> Vec<Output<'a>> {
    let dir = rig.parent().unwrap_or(Path::new(""));
    entry
        .iter()
        .filter_map(|(key, value)| {
            let key = key.replace('-', "_");
            if !kind.output_keys.contains(&key.as_str()) {
                return None;
            }
            let written = match &value.value {
                RawValue::Text(t) => t.clone(),
                RawValue::Integer(i) => i.to_string(),
                RawValue::Number(x) => x.to_string(),
                RawValue::List(items) if items.len() == 1 => items[0].text(),
                RawValue::Flag(_) | RawValue::List(_) => return None,
            };
            let shown = lexically_normal(&dir.join(&written));
            Some(Output {
                at: pos(value),
                device,
                key,
                same: same_file_key(&shown),
                written,
                shown,
            })
        })
        .collect()
}

/// The first output (in file order) that names a file an earlier one names too: its place and
/// the message naming both devices, both keys and the file.
fn shared_output(mut outputs: Vec<Output<'_>>) -> Option<(Pos, String)> {
    outputs.sort_by_key(|o| (o.at.line, o.at.column));
    outputs.iter().enumerate().find_map(|(k, later)| {
        let earlier = outputs[..k].iter().find(|o| o.same == later.same)?;
        let whose = if earlier.device == later.device {
            "its own".to_owned()
        } else {
            format!("device `{}`'s", earlier.device)
        };
        Some((
            later.at,
            format!(
                "device `{}`: `{}: {}` and {whose} `{}:` (line {}) are one file, {}: one would \
                 overwrite the other; give each its own file",
                later.device,
                later.key,
                later.written,
                earlier.key,
                earlier.at.line,
                later.shown.display()
            ),
        ))
    })
}

/// `path` with `.` left out and each `..` taking out the name before it, without asking the
/// file system (the file need not exist yet): `rigs/./a/../x.json` → `rigs/x.json`. A `..`
/// with no name before it stays (`../x.json`), as does one after the root (`/..` is `/`).
fn lexically_normal(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out: Vec<Component<'_>> = Vec::new();
    for component in path.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => match out.last() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(component),
            },
            other => out.push(other),
        }
    }
    if out.is_empty() {
        return PathBuf::from(".");
    }
    out.iter().collect()
}

/// What two names of one file share: the lexically normal path made absolute (from the
/// working folder) and, when its folder exists, that folder as the file system names it
/// (through symbolic links: `/tmp/x` and `/private/tmp/x` on macOS). The file itself need not
/// exist.
fn same_file_key(normal: &Path) -> PathBuf {
    let absolute = std::path::absolute(normal)
        .map(|p| lexically_normal(&p))
        .unwrap_or_else(|_| normal.to_owned());
    let real = absolute
        .parent()
        .zip(absolute.file_name())
        .and_then(|(dir, name)| std::fs::canonicalize(dir).ok().map(|dir| dir.join(name)));
    real.unwrap_or(absolute)
}
fn check_name(name: &str) -> Result<(), String> {
    let fine = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
    if name.is_empty() || name.chars().count() > MAX_NAME_CHARS || !name.chars().all(fine) {
        return Err(format!(
            "device name `{name}`: use 1 to {MAX_NAME_CHARS} letters, digits, `_` or `-`"
        ));
    }
    Ok(())
}

fn kind_of(kinds: &[SimKind], entry: &Entry, at: Pos) -> Result<SimKind, (Pos, String)> {
    let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
    let Some(value) = entry.get("kind") else {
        return Err((at, format!("no `kind:` (one of {})", names.join(", "))));
    };
    let word = match &value.value {
        RawValue::Text(word) => word.as_str(),
        _ => "",
    };
    kinds
        .iter()
        .copied()
        .find(|k| k.name() == word)
        .ok_or_else(|| {
            (
                pos(value),
                format!(
                    "unknown kind `{word}`{}; a rig holds {}",
                    suggestion(word, &names),
                    names.join(", ")
                ),
            )
        })
}

/// The command line of one entry: each key an option (`state_file` → `--state-file=…`), `true`
/// a bare flag, `false` left out, a list the option once per item; the kind's positional keys
/// last, after `--`.
fn command_line(kind: SimKind, entry: &Entry) -> Result<Vec<String>, (Pos, String)> {
    let mut options = Vec::new();
    let mut positional = Vec::new();
    for (key, value) in entry.iter().filter(|(k, _)| k.as_str() != "kind") {
        let option = format!("--{}", key.replace('_', "-"));
        let words: Vec<String> = match &value.value {
            RawValue::Flag(set) => {
                if kind.positional_keys.contains(&key.as_str()) {
                    return Err((pos(value), format!("`{key}:` takes a value, not {set}")));
                }
                if *set {
                    options.push(option);
                }
                continue;
            }
            RawValue::Integer(i) => vec![i.to_string()],
            RawValue::Number(x) => vec![x.to_string()],
            RawValue::Text(t) => vec![t.clone()],
            RawValue::List(items) => items.iter().map(RawItem::text).collect(),
        };
        if kind.positional_keys.contains(&key.as_str()) {
            if words.len() != 1 {
                return Err((pos(value), format!("`{key}:` takes one value, not a list")));
            }
            positional.extend(words);
        } else {
            options.extend(words.iter().map(|w| format!("{option}={w}")));
        }
    }
    if !positional.is_empty() {
        options.push("--".to_owned());
        options.extend(positional);
    }
    Ok(options)
}
