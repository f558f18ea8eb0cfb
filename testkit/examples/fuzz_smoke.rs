//! CI's fuzz smoke run: every fuzz target's entry point on its seeds and the inputs kept in
//! `fuzz/regressions/<target>/`, then on random mutations of them for a fixed time, two
//! targets at a time. A panicking input is written to `fuzz/regressions/<target>/`, where
//! `cargo test` replays it, and the run exits 1.
//!
//! `cargo run -p armhil-testkit --features fuzz --example fuzz_smoke -- [--seconds N]
//! [--seed S] [TARGET...]` (defaults: 10 s per target, seed 1, every target). Coverage-guided
//! runs are `scripts/fuzz.sh` (docs/fuzzing.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use testkit::fuzz::smoke::{self, SmokeReport};
use testkit::fuzz::{Entry, TARGETS};
use testkit::fuzz_seeds;

struct Options {
    seconds: u64,
    seed: u64,
    targets: Vec<(&'static str, Entry)>,
}

fn parse_args() -> Result<Options, String> {
    let mut options = Options {
        seconds: 10,
        seed: 1,
        targets: Vec::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut number = |flag: &str| -> Result<u64, String> {
            let value = args.next().ok_or(format!("{flag} needs a number"))?;
            value
                .parse()
                .map_err(|_| format!("{flag}: not a whole number: {value:?}"))
        };
        match arg.as_str() {
            "--seconds" => options.seconds = number("--seconds")?,
            "--seed" => options.seed = number("--seed")?,
            name => {
                let target = TARGETS.iter().find(|(n, _)| *n == name).ok_or_else(|| {
                    let names: Vec<&str> = TARGETS.iter().map(|(n, _)| *n).collect();
                    format!(
                        "unknown fuzz target {name:?} (targets: {})",
                        names.join(", ")
                    )
                })?;
                options.targets.push(*target);
            }
        }
    }
    if options.targets.is_empty() {
        options.targets = TARGETS.to_vec();
    }
    Ok(options)
}

/// The seeds built from the fixtures and scenarios, and every input kept for the target.
fn inputs(root: &Path, target: &str) -> std::io::Result<Vec<Vec<u8>>> {
    let mut inputs: Vec<Vec<u8>> = fuzz_seeds::seeds(target, root)?
        .into_iter()
        .map(|(_, bytes)| bytes)
        .collect();
    if let Ok(kept) = std::fs::read_dir(regressions(root, target)) {
        for file in kept {
            inputs.push(std::fs::read(file?.path())?);
        }
    }
    Ok(inputs)
}

fn regressions(root: &Path, target: &str) -> PathBuf {
    root.join("fuzz/regressions").join(target)
}

/// Keeps a crashing input where `cargo test` replays it; its name is a hash of the bytes.
fn keep(root: &Path, target: &str, input: &[u8]) -> std::io::Result<PathBuf> {
    // FNV-1a: a stable name for the same bytes, no dependency needed for it.
    let hash = input.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    });
    let dir = regressions(root, target);
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("smoke-{hash:016x}"));
    std::fs::write(&path, input)?;
    Ok(path)
}

fn main() -> ExitCode {
    let options = match parse_args() {
        Ok(options) => options,
        Err(message) => {
            eprintln!("fuzz_smoke: {message}");
            return ExitCode::from(2);
        }
    };
    // The repository root, one level above this crate.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let started = Instant::now();
    // The caught panics' messages are reported below; the default hook would print each
    // one a second time.
    std::panic::set_hook(Box::new(|_| {}));
    let queue = Mutex::new(options.targets.iter());
    let results = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let Some(&(name, entry)) = queue.lock().expect("queue").next() else {
                    return;
                };
                let outcome = inputs(&root, name).map(|seeds| {
                    let time = Duration::from_secs(options.seconds);
                    (seeds.len(), smoke::run(entry, &seeds, time, options.seed))
                });
                results.lock().expect("results").push((name, outcome));
            });
        }
    });
    let _ = std::panic::take_hook();

    let mut results = results.into_inner().expect("results");
    results.sort_by_key(|(name, _)| *name);
    println!(
        "\n{:<24} {:>6} {:>11} {:>8}  result",
        "target", "seeds", "executions", "exec/s"
    );
    let mut failed = false;
    for (name, outcome) in results {
        match outcome {
            Err(error) => {
                failed = true;
                println!("{name:<24} cannot read its seeds: {error}");
            }
            Ok((seeds, SmokeReport { executions, crash })) => {
                let rate = executions as f64 / options.seconds.max(1) as f64;
                let verdict = match crash {
                    None => "ok".to_owned(),
                    Some((input, message)) => {
                        failed = true;
                        match keep(&root, name, &input) {
                            Ok(path) => {
                                format!("CRASH: {message} (input kept in {})", path.display())
                            }
                            Err(e) => format!("CRASH: {message} (input not kept: {e})"),
                        }
                    }
                };
                println!("{name:<24} {seeds:>6} {executions:>11} {rate:>8.0}  {verdict}");
            }
        }
    }
    println!(
        "fuzz smoke: {} target(s), {} s each, seed {}, {:.0} s in all",
        options.targets.len(),
        options.seconds,
        options.seed,
        started.elapsed().as_secs_f64()
    );
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
