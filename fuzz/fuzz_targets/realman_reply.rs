//! Fuzz target `realman_reply`: see `testkit::fuzz::realman_reply` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::realman_reply(data));
