//! Fuzz target `scenario_check`: see `armhil_fuzz::scenario_check` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::scenario_check(data));
