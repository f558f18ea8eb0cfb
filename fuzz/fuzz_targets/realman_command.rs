//! Fuzz target `realman_command`: see `armhil_fuzz::realman_command` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::realman_command(data));
