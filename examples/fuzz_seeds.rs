//! Writes the seed corpus of the fuzz targets (built from `fixtures/` and `scenarios/`) into
//! `OUT/<target>/`: `cargo run --example fuzz_seeds -- OUT [TARGET...]` (all targets by
//! default). Used by `scripts/fuzz.sh`; see `docs/fuzzing.md`.

#[path = "../fuzz/harness/mod.rs"]
#[allow(dead_code)]
mod fuzz_harness;

use std::path::{Path, PathBuf};

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let Some(out) = args.next().map(PathBuf::from) else {
        eprintln!("usage: fuzz_seeds OUT_DIR [TARGET...]");
        std::process::exit(2);
    };
    let mut targets: Vec<String> = args.collect();
    if targets.is_empty() {
        targets = fuzz_harness::TARGETS
            .iter()
            .map(|(n, _)| n.to_string())
            .collect();
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for target in &targets {
        let dir = out.join(target);
        std::fs::create_dir_all(&dir)?;
        let seeds = fuzz_harness::seeds::seeds(target, root)?;
        for (name, bytes) in &seeds {
            std::fs::write(dir.join(name), bytes)?;
        }
        println!("{target}: {} seed(s)", seeds.len());
    }
    Ok(())
}
