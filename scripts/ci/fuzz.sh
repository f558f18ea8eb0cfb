#!/usr/bin/env bash
# CI's fuzz smoke run: every fuzz target built (fuzz/Cargo.toml's quick dev profile, no
# sanitizer) and run for a few seconds from its seeds, two at a time on the 2 cores, failing
# on a crash; the crashing input is copied to fuzz/regressions/<target>/ (commit it: `cargo
# test` then replays it). The long runs, optimised and under AddressSanitizer, are
# scripts/fuzz.sh, run before a release (docs/fuzzing.md).
#
# FUZZ_BUDGET_S (default 300) bounds the whole step: installing cargo-fuzz when missing, the
# build and the runs. A build that cannot finish in what is left after reserving the runs'
# time is stopped, and the step exits 75 ("skipped for time", which .ci/run shows in its
# table without failing): a slow machine is not a defect of the code. A build error or a
# crash fails the step. Time the build leaves over lengthens the runs.
# Needs only the stable toolchain (scripts/fuzz.sh sets RUSTC_BOOTSTRAP=1 for cargo-fuzz).
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$(date +%s)
budget=${FUZZ_BUDGET_S:-300}
secs=${FUZZ_SECONDS:-5}
jobs=${FUZZ_JOBS:-2}
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi
status=0
FUZZ_BUILD=${FUZZ_BUILD:-smoke} FUZZ_SANITIZER=${FUZZ_SANITIZER:-none} FUZZ_JOBS=$jobs \
    FUZZ_RUN_UNTIL=$((start + budget - 5)) scripts/fuzz.sh "$secs" || status=$?
echo "ci/fuzz: $(($(date +%s) - start)) s in all"
if ((status == 3)); then
    echo "ci/fuzz: SKIPPED for time (the fuzz build needed more than the budget left it)"
    exit 75
fi
exit $status
