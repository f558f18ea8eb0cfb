#!/usr/bin/env bash
# CI: every fuzz target for at least 60 s (FUZZ_SECONDS to change), two at a time on the 2
# cores (FUZZ_JOBS), failing on a crash. The crashing input is copied to
# fuzz/regressions/<target>/ (keep it as the regression test: commit it).
#
# FUZZ_BUDGET_S (default 1500) bounds the whole step: cargo-fuzz install, the sanitizer build
# (the longest build of all) and the runs. A build that cannot finish in what is left after
# reserving the runs' time is stopped and the step reports "SKIPPED for time" and passes: a
# slow machine is not a defect of the code. A build error or a crash fails the step. What a
# fast build leaves of the budget lengthens the runs.
# Needs only the stable toolchain (scripts/fuzz.sh sets RUSTC_BOOTSTRAP=1 for cargo-fuzz).
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$(date +%s)
budget=${FUZZ_BUDGET_S:-1500}
secs=${FUZZ_SECONDS:-60}
jobs=${FUZZ_JOBS:-2}
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi
status=0
FUZZ_JOBS=$jobs FUZZ_RUN_UNTIL=$((start + budget - 30)) scripts/fuzz.sh "$secs" || status=$?
echo "ci/fuzz: $(($(date +%s) - start)) s in all"
if (( status == 3 )); then
    echo "ci/fuzz: SKIPPED for time (the fuzz build needed more than the budget left it)"
    exit 0
fi
exit $status
