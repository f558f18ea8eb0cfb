//! The Damiao driver: its codec against every vector of `fixtures/damiao/`, property tests of
//! the codec, and the motor handles against a scripted responder on the virtual bus that
//! replays the fixtures' replies (raw bytes, never the emulator's code).

mod motor;
mod props;
mod vectors;

use std::collections::BTreeMap;

use driver::damiao::{Model, RangeTable, Ranges};
use testkit::fixtures::Vector;

/// The fixture files the tests know; another file in the folder fails `vectors`.
const FILES: [&str; 3] = ["commands.log", "feedback.log", "registers.log"];

/// Every vector of `fixtures/damiao/`, by name; a name used twice fails.
fn vectors() -> BTreeMap<String, Vector> {
    let dir = testkit::fixtures::repo_path("damiao");
    let mut out = BTreeMap::new();
    for v in testkit::fixtures::read_dir(dir).unwrap_or_else(|e| panic!("{e}")) {
        if let Some(old) = out.insert(v.name.clone(), v) {
            panic!("{}: vector name {} used twice", old.at, old.name);
        }
    }
    out
}

fn f(v: &Vector, key: &str) -> f64 {
    v.float(key).unwrap_or_else(|e| panic!("{e}"))
}

fn int(v: &Vector, key: &str) -> i64 {
    v.int(key).unwrap_or_else(|e| panic!("{e}"))
}

fn text<'a>(v: &'a Vector, key: &str) -> &'a str {
    v.text(key).unwrap_or_else(|e| panic!("{e}"))
}

/// ESC_ID and MST_ID of a vector.
fn ids(v: &Vector) -> (u16, u16) {
    (int(v, "esc_id") as u16, int(v, "mst_id") as u16)
}

/// The vector's model ranges (the current table).
fn ranges(v: &Vector) -> Ranges {
    Model::parse(text(v, "model"))
        .unwrap_or_else(|| panic!("{}: unknown model", v.name))
        .ranges(RangeTable::Current)
}
