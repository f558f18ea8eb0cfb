//! A quick, dependency-free smoke run of the fuzz entry points: seeds and random mutations of
//! them, for a fixed time per target, in whatever build is at hand.
//!
//! Why not libFuzzer: its instrumented build of the whole tree (rapier included) takes about
//! 11 minutes of CPU from nothing, more than CI's five-minute smoke step; this runs in the dev
//! build `cargo test` already made. It is blind to coverage, so it finds shallow defects only;
//! the coverage-guided runs under AddressSanitizer stay in `scripts/fuzz.sh` (docs/fuzzing.md).

use std::panic::{self, AssertUnwindSafe};
use std::time::{Duration, Instant};

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

use super::Entry;

/// Inputs longer than this are cut (libFuzzer's `-max_len` in scripts/fuzz.sh is the same).
pub const MAX_INPUT_LEN: usize = 8192;

/// What one target's smoke run did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SmokeReport {
    /// Inputs run: seeds and mutants.
    pub executions: u64,
    /// The first input that panicked, and the panic's message; `None` when none did.
    pub crash: Option<(Vec<u8>, String)>,
}

/// Runs `entry` on every seed, then on mutants of the seeds until `time` has passed or an
/// input panics. The mutations are drawn from `rng_seed`, so a run with the same seeds, seed
/// and iteration count repeats exactly.
pub fn run(entry: Entry, seeds: &[Vec<u8>], time: Duration, rng_seed: u64) -> SmokeReport {
    let deadline = Instant::now() + time;
    let mut rng = SmallRng::seed_from_u64(rng_seed);
    let mut executions = 0;
    let empty = [Vec::new()];
    let pool = if seeds.is_empty() { &empty[..] } else { seeds };
    for seed in pool {
        executions += 1;
        if let Err(message) = run_one(entry, seed) {
            return SmokeReport {
                executions,
                crash: Some((seed.clone(), message)),
            };
        }
    }
    while Instant::now() < deadline {
        let input = mutant(&mut rng, pool);
        executions += 1;
        if let Err(message) = run_one(entry, &input) {
            return SmokeReport {
                executions,
                crash: Some((input, message)),
            };
        }
    }
    SmokeReport {
        executions,
        crash: None,
    }
}

/// One input through `entry`; a panic becomes its message.
fn run_one(entry: Entry, input: &[u8]) -> Result<(), String> {
    panic::catch_unwind(AssertUnwindSafe(|| entry(input))).map_err(|payload| {
        payload
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_owned()))
            .unwrap_or_else(|| "a panic without a message".to_owned())
    })
}

/// A seed changed by one to four of the mutations libFuzzer also starts with: flip a bit, set
/// a byte to an interesting value, insert or delete a run, copy a run within the input, or
/// splice in part of another seed.
pub fn mutant(rng: &mut SmallRng, seeds: &[Vec<u8>]) -> Vec<u8> {
    let mut data = seeds[rng.random_range(0..seeds.len())].clone();
    for _ in 0..rng.random_range(1..=4) {
        mutate_once(rng, &mut data, seeds);
    }
    data.truncate(MAX_INPUT_LEN);
    data
}

const INTERESTING: [u8; 9] = [0x00, 0x01, 0x7F, 0x80, 0xFF, b'\n', b'{', b'}', b'"'];

fn mutate_once(rng: &mut SmallRng, data: &mut Vec<u8>, seeds: &[Vec<u8>]) {
    if data.is_empty() {
        data.push(rng.random());
        return;
    }
    let at = rng.random_range(0..data.len());
    match rng.random_range(0..7) {
        0 => data[at] ^= 1 << rng.random_range(0..8),
        1 => data[at] = INTERESTING[rng.random_range(0..INTERESTING.len())],
        2 => data[at] = rng.random(),
        3 => {
            let run: Vec<u8> = (0..rng.random_range(1..=8)).map(|_| rng.random()).collect();
            data.splice(at..at, run);
        }
        4 => {
            let end = (at + rng.random_range(1..=16)).min(data.len());
            data.drain(at..end);
        }
        5 => {
            let end = (at + rng.random_range(1..=16)).min(data.len());
            let copy = data[at..end].to_vec();
            let to = rng.random_range(0..=data.len());
            data.splice(to..to, copy);
        }
        _ => {
            let other = &seeds[rng.random_range(0..seeds.len())];
            if !other.is_empty() {
                let from = rng.random_range(0..other.len());
                let end = (from + rng.random_range(1..=64)).min(other.len());
                data.splice(at..at, other[from..end].iter().copied());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panics_on_three_zero_bytes(data: &[u8]) {
        assert!(!data.windows(3).any(|w| w == [0, 0, 0]), "three zero bytes");
    }

    fn never_panics(_: &[u8]) {}

    #[test]
    fn a_panic_reached_by_mutation_is_reported_with_its_input() {
        let seeds = vec![vec![0, 0, 1, 5, 9]];
        let report = run(
            panics_on_three_zero_bytes,
            &seeds,
            Duration::from_secs(10),
            7,
        );
        let (input, message) = report.crash.expect("mutations reach three zero bytes");
        assert!(input.windows(3).any(|w| w == [0, 0, 0]), "{input:?}");
        assert!(message.contains("three zero bytes"), "{message}");
        assert!(report.executions > 1, "found by a mutant, not the seed");
    }

    #[test]
    fn a_crashing_seed_is_reported_before_any_mutation() {
        let seeds = vec![vec![1], vec![0, 0, 0]];
        let report = run(panics_on_three_zero_bytes, &seeds, Duration::ZERO, 1);
        assert_eq!(report.executions, 2);
        assert_eq!(report.crash.map(|(input, _)| input), Some(vec![0, 0, 0]));
    }

    #[test]
    fn a_clean_target_runs_until_its_time_is_up() {
        let report = run(
            never_panics,
            &[b"seed".to_vec()],
            Duration::from_millis(50),
            3,
        );
        assert_eq!(report.crash, None);
        assert!(report.executions > 100, "{} executions", report.executions);
    }

    #[test]
    fn mutants_differ_and_stay_within_the_length_limit() {
        let mut rng = SmallRng::seed_from_u64(11);
        let seeds = vec![vec![0xAA; MAX_INPUT_LEN]];
        let mutants: Vec<Vec<u8>> = (0..200).map(|_| mutant(&mut rng, &seeds)).collect();
        assert!(mutants.iter().all(|m| m.len() <= MAX_INPUT_LEN));
        assert!(mutants.iter().filter(|m| **m != seeds[0]).count() > 150);
    }
}
