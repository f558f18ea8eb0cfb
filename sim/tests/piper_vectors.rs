//! Reader for the candump fixture files (`fixtures/piper/*.log`) shared by the Piper tests.
//! Included by the other `piper_*` test files with `#[path]`; on its own it has no tests.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::PathBuf;

use bus::CanFrame;

/// One vector: the comment(s) before a frame and the frame.
#[derive(Debug)]
pub struct Vector {
    /// Fixture file name.
    pub file: String,
    /// 1-based line of the vector comment.
    pub line: usize,
    /// CAN id named by the comment.
    pub id: u16,
    /// Vector name (`arm_status`, `mode_ctrl`, …).
    pub name: String,
    /// Decoded fields as written.
    pub fields: BTreeMap<String, String>,
    /// The frame.
    pub frame: CanFrame,
    /// 1-based line of the frame itself (several comments may share it).
    pub frame_line: usize,
    /// Name of the `## exchange <name>:` block the vector is in (empty outside blocks).
    pub block: String,
}

impl Vector {
    /// Whether the comment lists `key`.
    pub fn has(&self, key: &str) -> bool {
        self.fields.contains_key(key)
    }
    /// Integer field (decimal or 0x hex).
    pub fn get(&self, key: &str) -> i64 {
        let v = self
            .fields
            .get(key)
            .unwrap_or_else(|| panic!("{}:{} has no {key}", self.file, self.line));
        if let Some(hex) = v.strip_prefix("0x") {
            i64::from_str_radix(hex, 16).unwrap()
        } else {
            v.parse().unwrap_or_else(|_| {
                panic!("{}:{}: {key}={v} is not a number", self.file, self.line)
            })
        }
    }
    /// Float field.
    pub fn f(&self, key: &str) -> f64 {
        self.fields[key].parse().unwrap()
    }
    /// String field.
    pub fn s(&self, key: &str) -> &str {
        &self.fields[key]
    }
    /// The `expect=` handling, if any.
    pub fn expect(&self) -> Option<&str> {
        self.fields.get("expect").map(String::as_str)
    }
    /// Location for assertion messages.
    pub fn at(&self) -> String {
        format!(
            "{}:{} ({:03X} {})",
            self.file, self.line, self.id, self.name
        )
    }
}

/// `fixtures/piper/`.
pub fn fixtures_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/piper")
}

/// `ID#HEX` → frame.
pub fn parse_frame(text: &str) -> CanFrame {
    let (id, data) = text.split_once('#').unwrap();
    let id = u16::from_str_radix(id, 16).unwrap();
    let bytes: Vec<u8> = (0..data.len() / 2)
        .map(|i| u8::from_str_radix(&data[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    CanFrame::standard(id, &bytes).unwrap()
}

/// Every vector in every `*.log` of the fixture directory (sorted by file name).
pub fn load() -> Vec<Vector> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(fixtures_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "log"))
        .collect();
    files.sort();
    let mut out = Vec::new();
    for path in files {
        let file = path.file_name().unwrap().to_string_lossy().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        let mut pending: Vec<(usize, u16, String, BTreeMap<String, String>)> = Vec::new();
        let mut block = String::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if let Some(rest) = line.strip_prefix("## exchange ") {
                block = rest
                    .split(':')
                    .next()
                    .unwrap_or_default()
                    .trim()
                    .to_string();
                continue;
            }
            if line.starts_with("##") || line.is_empty() {
                continue;
            }
            if let Some(comment) = line.strip_prefix('#') {
                let comment = comment.trim();
                let (head, rest) = comment.split_once(':').unwrap();
                let (id, name) = head.split_once(' ').unwrap();
                let fields = rest
                    .split_whitespace()
                    .filter_map(|kv| kv.split_once('='))
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect();
                pending.push((
                    n + 1,
                    u16::from_str_radix(id, 16).unwrap(),
                    name.to_string(),
                    fields,
                ));
                continue;
            }
            // `(time) iface ID#DATA`
            let frame = parse_frame(line.split_whitespace().nth(2).unwrap());
            for (line, id, name, fields) in pending.drain(..) {
                out.push(Vector {
                    file: file.clone(),
                    line,
                    id,
                    name,
                    fields,
                    frame,
                    frame_line: n + 1,
                    block: block.clone(),
                });
            }
        }
    }
    out
}
