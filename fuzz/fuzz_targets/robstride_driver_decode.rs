//! Fuzz target `robstride_driver_decode`: see `armhil_fuzz::robstride_driver_decode` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::robstride_driver_decode(data));
