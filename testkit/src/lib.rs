//! Test support shared by armhil's crates, used only as a dev-dependency (and by the cargo-fuzz
//! crate), so no library of armhil ships test code.
//!
//! - [`fixtures`]: the annotated candump test vectors in `fixtures/` that the drivers and the
//!   emulators are both checked against.
//! - [`transcript`]: the JSON test-vector transcripts of the Realman fixtures.
//! - [`tools`]: tests that need a program from outside (tshark, can-utils) ask here whether it
//!   is on `PATH`; missing, the test is skipped with one line, or fails under
//!   `ARMHIL_REQUIRE_TOOLS=1` (CI).
//! - `emulators` (feature `emulators`): an emulator on a fresh virtual bus or in-memory
//!   streams, and small clients to talk to it.
//! - `fuzz` (feature `fuzz`): one entry point per fuzz target, replayed by `cargo test` over
//!   every kept regression input; [`fuzz_seeds`] writes their seed corpora.

pub mod fixtures;
pub mod fuzz_seeds;
pub mod tools;
pub mod transcript;

#[cfg(feature = "emulators")]
pub mod corpus;
#[cfg(feature = "emulators")]
pub mod emulators;
#[cfg(feature = "fuzz")]
pub mod fuzz;
