//! Fuzz target `scenario_check`: see `testkit::fuzz::scenario_check` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::scenario_check(data));
