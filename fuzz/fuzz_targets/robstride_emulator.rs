//! Fuzz target `robstride_emulator`: see `armhil_fuzz::robstride_emulator` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::robstride_emulator(data));
