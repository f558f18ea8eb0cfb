#!/usr/bin/env bash
# Source coverage reached by fuzz corpora (`cargo fuzz coverage`).
#
#   scripts/fuzz-coverage.sh CORPUS_ROOT [TARGET...]     (default: every target with a corpus)
#
# CORPUS_ROOT holds one folder per target, as `FUZZ_WORK_DIR=... scripts/fuzz.sh` leaves in
# $FUZZ_WORK_DIR/corpus. For each target this builds the coverage-instrumented binary, runs every
# corpus input through it once (no fuzzing), and prints the lines of armhil's own code it
# reached, per source file it entered and over those files. An HTML
# report per target goes to out/fuzz-coverage/<target>/index.html.
#
# Needs the rustup component llvm-tools (`rustup component add llvm-tools`), and, like
# scripts/fuzz.sh, sets RUSTC_BOOTSTRAP=1 so the stable toolchain accepts cargo-fuzz's flags.
#
# Environment:
#   FUZZ_COVERAGE_TARGET_DIR  cargo target dir of the instrumented build (default:
#                             target/fuzz-coverage; its own, since every crate is rebuilt)
set -euo pipefail

cd "$(dirname "$0")/.."
root=$PWD
if [ $# -lt 1 ] || [ ! -d "$1" ]; then
    echo "usage: scripts/fuzz-coverage.sh CORPUS_ROOT [TARGET...] (CORPUS_ROOT: a folder of" \
        "per-target corpus folders)" >&2
    exit 2
fi
corpus_root=$(cd "$1" && pwd)
shift

sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
llvm_bin=$sysroot/lib/rustlib/$host/bin
if [ ! -x "$llvm_bin/llvm-cov" ]; then
    echo "fuzz-coverage: $llvm_bin/llvm-cov not found; run: rustup component add llvm-tools" >&2
    exit 2
fi

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    for f in fuzz/fuzz_targets/*.rs; do
        t=$(basename "$f" .rs)
        [ -d "$corpus_root/$t" ] && targets+=("$t")
    done
fi
if [ ${#targets[@]} -eq 0 ]; then
    echo "fuzz-coverage: no corpus folder for any target in $corpus_root" >&2
    exit 2
fi

target_dir=${FUZZ_COVERAGE_TARGET_DIR:-$root/target/fuzz-coverage}
mkdir -p "$target_dir"
export RUSTC_BOOTSTRAP=1
summary=$(mktemp)
trap 'rm -f "$summary"' EXIT

for t in "${targets[@]}"; do
    if [ ! -d "$corpus_root/$t" ]; then
        echo "fuzz-coverage: no corpus for $t in $corpus_root" >&2
        exit 2
    fi
    inputs=$(find "$corpus_root/$t" -type f | wc -l)
    echo "fuzz-coverage: $t: $inputs corpus inputs"
    # Without a sanitizer: coverage instrumentation and AddressSanitizer do not mix well, and
    # the lines reached do not depend on it.
    cargo fuzz coverage --fuzz-dir fuzz --target-dir "$target_dir" --release --sanitizer none \
        "$t" "$corpus_root/$t" >"$target_dir/$t.log" 2>&1 || {
        echo "fuzz-coverage: cargo fuzz coverage failed for $t (log: $target_dir/$t.log)" >&2
        tail -n 20 "$target_dir/$t.log" >&2
        exit 1
    }
    # Where cargo-fuzz leaves the instrumented binary: under the given target dir as is, or
    # (without --target-dir, in older versions) under a coverage/ sub-folder.
    bin=$target_dir/$host/release/$t
    [ -x "$bin" ] || bin=$target_dir/$host/coverage/$host/release/$t
    profile=fuzz/coverage/$t/coverage.profdata
    # Only the project's own sources: not the registry crates nor the standard library.
    ignore='(/\.cargo/|/rustc/|/rustlib/|^/usr/)'
    "$llvm_bin/llvm-cov" show "$bin" -instr-profile="$profile" -format=html \
        -ignore-filename-regex="$ignore" -output-dir="out/fuzz-coverage/$t" >/dev/null
    "$llvm_bin/llvm-cov" export "$bin" -instr-profile="$profile" -summary-only \
        -ignore-filename-regex="$ignore" |
        python3 "$root/scripts/fuzz-coverage-summary.py" "$t" "$root" | tee -a "$summary"
done

echo
printf '%-24s %9s %9s %8s %9s\n' target covered lines percent linked
awk '$1 == "TOTAL" { printf "%-24s %9d %9d %7.1f%% %9d\n", $2, $3, $4, $5, $6 }' "$summary"
echo "(lines of armhil's own files the corpus entered; linked: all of armhil's lines in the target)"
echo "fuzz-coverage: HTML reports in out/fuzz-coverage/<target>/index.html"
