//! Fuzz target `damiao_emulator`: see `testkit::fuzz::damiao_emulator` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::damiao_emulator(data));
