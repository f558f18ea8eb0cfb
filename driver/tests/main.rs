//! Integration tests of the drivers (`driver`), one test binary for the whole crate so a
//! 2-core machine links it once: `cargo test -p armhil-driver --test integration realman::client` runs
//! one module.
//!
//! - `damiao`, `piper`, `realman`, `robstride`: each driver's codec against the shared
//!   fixtures, and its client against a scripted device built from raw bytes (never the
//!   emulator's codec).
//! - `codec_props`: property tests of the drivers' own codecs.

mod codec_props;
mod damiao;
mod piper;
mod realman;
mod robstride;
