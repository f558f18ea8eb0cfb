//! Replays every input kept in `fuzz/regressions/<target>/` (crashes the fuzzers once found,
//! and seeds worth keeping) through the same entry point as the fuzz target, so a fixed
//! defect stays fixed without libFuzzer or a nightly toolchain.

use std::path::Path;

use testkit::fuzz as fuzz_harness;
use testkit::fuzz_seeds;

#[test]
fn every_kept_fuzz_input_passes_its_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    let mut replayed = 0;
    let Ok(dirs) = std::fs::read_dir(&root) else {
        return;
    };
    for dir in dirs {
        let dir = dir.expect("listing fuzz/regressions").path();
        if !dir.is_dir() {
            continue;
        }
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let entry = fuzz_harness::entry(name)
            .unwrap_or_else(|| panic!("fuzz/regressions/{name}: no fuzz target of that name"));
        for file in std::fs::read_dir(&dir).expect("listing a regression folder") {
            let path = file.expect("listing a regression folder").path();
            let data = std::fs::read(&path).expect("reading a regression input");
            eprintln!("replaying {}", path.display());
            entry(&data);
            replayed += 1;
        }
    }
    eprintln!("{replayed} fuzz regression input(s) replayed");
}

#[test]
fn every_target_accepts_empty_and_tiny_inputs() {
    for (name, entry) in fuzz_harness::TARGETS {
        for data in [&b""[..], b"\0", b"\xff\xff\xff\xff", b"{}\r\n"] {
            eprintln!("{name} {data:?}");
            entry(data);
        }
    }
}

#[test]
fn every_seed_passes_its_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, entry) in fuzz_harness::TARGETS {
        let seeds = fuzz_seeds::seeds(name, root).expect("reading the fixtures");
        assert!(!seeds.is_empty(), "{name}: no seeds");
        for (seed, data) in seeds {
            eprintln!("{name} {seed}");
            entry(&data);
        }
    }
}
