//! Fuzz target `candump_reader`: see `armhil_fuzz::candump_reader` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::candump_reader(data));
