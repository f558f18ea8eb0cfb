//! Fuzz target `piper_driver_decode`: see `testkit::fuzz::piper_driver_decode` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::piper_driver_decode(data));
