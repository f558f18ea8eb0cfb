#!/usr/bin/env bash
# CI's fuzz smoke run, in about two minutes and at most FUZZ_BUDGET_S (default 300) with its
# builds:
#  1. the cargo-fuzz crate's targets compile (`cargo check`, reusing what the root
#     workspace's clippy run checked: the same dev profile and dependency versions);
#  2. every target's entry point runs on its seeds, the inputs kept in fuzz/regressions/,
#     and random mutations of them for FUZZ_SECONDS each (default 20), two targets at a
#     time (testkit's example `fuzz_smoke`, in the dev build `cargo test` made). A panicking
#     input is kept in fuzz/regressions/<target>/ (commit it: `cargo test` replays it) and
#     the step fails.
# Coverage-guided libFuzzer runs under AddressSanitizer are scripts/fuzz.sh, run before a
# release (docs/fuzzing.md): their instrumented build of the whole tree takes about 11
# minutes of CPU from nothing, more than this step may take.
# The mutations are seeded from the date (FUZZ_SEED to repeat a run), so successive CI runs
# try different inputs; the seed is printed.
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$(date +%s)
budget=${FUZZ_BUDGET_S:-300}
secs=${FUZZ_SECONDS:-20}
seed=${FUZZ_SEED:-$(date +%Y%m%d)}
targets=$(find fuzz/fuzz_targets -name '*.rs' | wc -l)
# Two at a time, plus about 30 s for the builds when the dependencies are built.
if ((targets * secs / 2 + 30 > budget)); then
    secs=$(((budget - 30) * 2 / targets))
    echo "ci/fuzz: ${secs}s per target to fit the ${budget}s budget"
fi

echo "---- cargo check of the fuzz targets (fuzz/)"
# A build that does not fit the budget is CI running short of time, not a finding: said and
# skipped (a smoke run that overruns is a hang, and fails).
rc=0
CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target} \
    timeout $((budget / 2)) cargo check --manifest-path fuzz/Cargo.toml --bins || rc=$?
if ((rc == 124)); then
    echo "ci/fuzz: the fuzz targets' build did not fit the ${budget}s budget; smoke run skipped"
    exit 0
elif ((rc != 0)); then
    exit "$rc"
fi
echo "---- smoke run: ${secs}s per target, seed $seed"
timeout $((budget - ($(date +%s) - start))) \
    cargo run --quiet -p armhil-testkit --features fuzz --example fuzz_smoke -- \
    --seconds "$secs" --seed "$seed"
echo "ci/fuzz: $(($(date +%s) - start)) s in all"
