//! Fuzz target `robstride_driver_decode`: see `testkit::fuzz::robstride_driver_decode` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::robstride_driver_decode(data));
