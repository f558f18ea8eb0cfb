//! Fuzz target `damiao_driver_decode`: see `testkit::fuzz::damiao_driver_decode` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::damiao_driver_decode(data));
