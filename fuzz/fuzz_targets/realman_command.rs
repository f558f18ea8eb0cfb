//! Fuzz target `realman_command`: see `testkit::fuzz::realman_command` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::realman_command(data));
