//! Fuzz target `pcap_reader`: see `armhil_fuzz::pcap_reader` (fuzz/harness/) for its input and invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| armhil_fuzz::pcap_reader(data));
