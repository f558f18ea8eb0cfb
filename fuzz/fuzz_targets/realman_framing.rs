//! Fuzz target `realman_framing`: see `armhil_fuzz::realman_framing` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::realman_framing(data));
