//! Fuzz target `realman_framing`: see `testkit::fuzz::realman_framing` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::realman_framing(data));
