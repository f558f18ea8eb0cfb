//! Fuzz target `robstride_emulator`: see `testkit::fuzz::robstride_emulator` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::robstride_emulator(data));
