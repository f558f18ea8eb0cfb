//! Fuzz target `piper_emulator`: see `armhil_fuzz::piper_emulator` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::piper_emulator(data));
