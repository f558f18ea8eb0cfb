//! Fuzz target `realman_reply`: see `armhil_fuzz::realman_reply` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::realman_reply(data));
