#!/usr/bin/env bash
# CI: every fuzz target for 60 s (FUZZ_SECONDS to change), two at a time on the 2 cores
# (FUZZ_JOBS), failing on a crash. The crashing
# input is copied to fuzz/regressions/<target>/ (keep it as the regression test: commit it).
# Needs only the stable toolchain (scripts/fuzz.sh sets RUSTC_BOOTSTRAP=1 for cargo-fuzz).
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$(date +%s)
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi
status=0
FUZZ_JOBS=${FUZZ_JOBS:-2} scripts/fuzz.sh "${FUZZ_SECONDS:-60}" || status=$?
echo "ci/fuzz: $(($(date +%s) - start)) s in all"
exit $status
