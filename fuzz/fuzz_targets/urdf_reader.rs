//! Fuzz target `urdf_reader`: see `testkit::fuzz::urdf_reader` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::urdf_reader(data));
