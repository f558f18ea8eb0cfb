//! Fuzz target `pcap_reader`: see `testkit::fuzz::pcap_reader` (testkit/src/fuzz/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| testkit::fuzz::pcap_reader(data));
