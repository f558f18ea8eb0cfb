//! Helpers shared by the harness's and the device kinds' unit tests.

use std::path::Path;

use super::parse_scenario;

/// The headline of the error `text` gives when read as `broken.yaml` (`file:line:col: message`);
/// panics when the scenario is valid or fails for another reason than its contents.
pub(crate) fn error_of(text: &str) -> String {
    match parse_scenario(Path::new("broken.yaml"), text) {
        Ok(_) => panic!("scenario unexpectedly valid:\n{text}"),
        Err(e) => e.scenario_error().expect("a scenario error").headline(),
    }
}
