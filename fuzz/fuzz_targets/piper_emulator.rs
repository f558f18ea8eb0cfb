//! Fuzz target `piper_emulator`: see `testkit::fuzz::piper_emulator` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::piper_emulator(data));
