//! The Piper fixtures (`fixtures/piper/*.log`) through `testkit::fixtures`, with the panicking
//! accessors the emulator's tests use (`fixtures` and `protocol`); on its own it has no tests.

pub use testkit::fixtures::Vector;

/// Every Piper fixture file the emulator's tests expect; a missing one fails the load.
pub const FILES: [&str; 8] = [
    "config.log",
    "cpv.log",
    "emu_exchanges.log",
    "feedback.log",
    "firmware.log",
    "malformed.log",
    "mit.log",
    "motion.log",
];

/// Test-side accessors: a missing or unreadable field is a test failure naming file and line.
pub trait PiperVector {
    /// Integer field (decimal or `0x` hex).
    fn get(&self, key: &str) -> i64;
    /// Real field.
    fn f(&self, key: &str) -> f64;
    /// Text field.
    fn s(&self, key: &str) -> &str;
    /// The 11-bit identifier.
    fn id16(&self) -> u16;
    /// Location and name for assertion messages.
    fn at(&self) -> String;
}

impl PiperVector for Vector {
    fn get(&self, key: &str) -> i64 {
        self.int(key).unwrap_or_else(|e| panic!("{e}"))
    }
    fn f(&self, key: &str) -> f64 {
        self.float(key).unwrap_or_else(|e| panic!("{e}"))
    }
    fn s(&self, key: &str) -> &str {
        self.text(key).unwrap_or_else(|e| panic!("{e}"))
    }
    fn id16(&self) -> u16 {
        // Piper fixtures hold standard frames only (11-bit identifiers).
        self.frame.raw_id() as u16
    }
    fn at(&self) -> String {
        self.to_string()
    }
}

/// Every vector of every Piper fixture file; the folder must hold exactly [`FILES`], so a
/// missing file or a new file nobody checks both fail.
pub fn load() -> Vec<Vector> {
    let dir = testkit::fixtures::repo_path("piper");
    let listed: Vec<String> = testkit::fixtures::list_dir(&dir)
        .unwrap_or_else(|e| panic!("{e}"))
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    assert_eq!(listed, FILES, "fixture files in {}", dir.display());
    FILES
        .iter()
        .flat_map(|f| testkit::fixtures::read_file(dir.join(f)).unwrap_or_else(|e| panic!("{e}")))
        .collect()
}
