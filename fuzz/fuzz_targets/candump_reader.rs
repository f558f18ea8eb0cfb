//! Fuzz target `candump_reader`: see `testkit::fuzz::candump_reader` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::candump_reader(data));
