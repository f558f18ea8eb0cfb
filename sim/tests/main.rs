//! Integration tests of the emulators (`sim`), one test binary for the whole crate so a
//! 2-core machine links it once: `cargo test -p armhil-sim --test integration piper::faults` runs one
//! module.
//!
//! - `piper`, `robstride`, `realman`, `damiao`: each emulator through its public API — on the virtual bus
//!   or in-memory streams, tick by tick, in the physics world, and against the shared fixtures.
//! - `codec_props`: property tests of the emulators' codecs.

mod codec_props;
mod corpus;
mod damiao;
mod piper;
mod realman;
mod robot;
mod robstride;
