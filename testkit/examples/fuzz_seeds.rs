//! Writes the seed corpus of armhil's fuzz targets (built from `fixtures/` and `scenarios/`)
//! into `OUT/<target>/`: `cargo run -p armhil-testkit --example fuzz_seeds -- OUT TARGET...`.
//! Used by `scripts/fuzz.sh`; see `docs/fuzzing.md`. The seeds need only the capture formats,
//! so with the testkit's default features building it does not build the physics engine.

use std::path::{Path, PathBuf};
use testkit::fuzz_seeds as seeds;

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let (Some(out), targets) = (args.next().map(PathBuf::from), args.collect::<Vec<_>>()) else {
        eprintln!("usage: fuzz_seeds OUT_DIR TARGET...");
        std::process::exit(2);
    };
    // The repository root, one level above this crate.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for target in &targets {
        let dir = out.join(target);
        std::fs::create_dir_all(&dir)?;
        let seeds = seeds::seeds(target, &root)?;
        if seeds.is_empty() {
            eprintln!("{target}: no seeds (unknown target?)");
            std::process::exit(2);
        }
        for (name, bytes) in &seeds {
            std::fs::write(dir.join(name), bytes)?;
        }
        println!("{target}: {} seed(s)", seeds.len());
    }
    Ok(())
}
