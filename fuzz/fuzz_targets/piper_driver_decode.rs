//! Fuzz target `piper_driver_decode`: see `armhil_fuzz::piper_driver_decode` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::piper_driver_decode(data));
