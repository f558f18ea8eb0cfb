//! Fuzz entry points: one function per fuzz target, each feeding arbitrary bytes through a
//! parser or state machine of armhil and asserting the invariants that must hold for any input.
//!
//! This module is shared by two users, so a crash found by a fuzzer replays exactly:
//!
//! - the cargo-fuzz crate in `fuzz/` (each target in `fuzz/fuzz_targets/` is one line calling
//!   a function here), built by `scripts/fuzz.sh`;
//! - the root crate's integration test `fuzz_regressions`, which replays every file kept in
//!   `fuzz/regressions/<target>/` through [`TARGETS`] inside `cargo test --workspace`.
//!
//! Only public APIs of the crates are used. A failed invariant panics (that is what libFuzzer
//! reports as a crash); an input that is merely invalid must return quietly.

mod damiao;
mod input;
mod logs;
mod piper;
mod realman;
mod robstride;
mod scenario;
pub mod smoke;
mod urdf;

pub use damiao::{damiao_driver_decode, damiao_emulator};
pub use logs::{candump_reader, pcap_reader};
pub use piper::{piper_driver_decode, piper_emulator};
pub use realman::{realman_command, realman_framing, realman_reply};
pub use robstride::{robstride_driver_decode, robstride_emulator};
pub use scenario::scenario_check;
pub use urdf::urdf_reader;

/// One fuzz entry point: takes the raw input, panics when an invariant fails.
pub type Entry = fn(&[u8]);

/// Every target by name (the name of its file in `fuzz/fuzz_targets/` and of its folder in
/// `fuzz/regressions/`).
pub const TARGETS: &[(&str, Entry)] = &[
    ("piper_emulator", piper_emulator),
    ("robstride_emulator", robstride_emulator),
    ("piper_driver_decode", piper_driver_decode),
    ("robstride_driver_decode", robstride_driver_decode),
    ("candump_reader", candump_reader),
    ("pcap_reader", pcap_reader),
    ("scenario_check", scenario_check),
    ("realman_framing", realman_framing),
    ("realman_command", realman_command),
    ("realman_reply", realman_reply),
    ("urdf_reader", urdf_reader),
    ("damiao_emulator", damiao_emulator),
    ("damiao_driver_decode", damiao_driver_decode),
];

/// The entry point of target `name`, if there is one.
pub fn entry(name: &str) -> Option<Entry> {
    TARGETS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}
