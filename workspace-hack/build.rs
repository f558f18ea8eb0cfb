//! Empty on purpose: cargo applies a package's `[build-dependencies]` only when it has a build
//! script, and this crate's build-dependencies exist to pin host-side features (see Cargo.toml).

fn main() {}
