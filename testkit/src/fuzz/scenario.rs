//! The scenario loader and checker behind `armhil check`.

use std::path::Path;

use armhil::harness::{parse_scenario, parse_variant};

/// Arbitrary text through scenario parsing and validation, as `armhil check` does for a file,
/// with and without a matrix variant.
///
/// Asserts: no panic, including while rendering the error message (which quotes the file's
/// text at a line and column).
pub fn scenario_check(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let path = Path::new("scenarios/fuzz.yaml");
    match parse_scenario(path, &text) {
        Ok(scenario) => {
            let _ = scenario.steps.len();
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
    // A file with a `matrix:` is checked once per value: try the first word of the input.
    let variant = text.split_whitespace().next().unwrap_or("piper");
    if let Err(e) = parse_variant(path, &text, Some(variant)) {
        let _ = e.to_string();
    }
}
