#!/usr/bin/env bash
# Run armhil's fuzz targets (fuzz/fuzz_targets/) for a given time each.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]      (default: 60 s, every target)
#
# Builds the seed corpus from fixtures/ and scenarios/ into a scratch folder, builds the
# targets with cargo-fuzz, runs them one after the other (one process each), and prints the
# executions and coverage of each. Exits non-zero if any target crashed; the crashing input
# is copied to fuzz/regressions/<target>/, where `cargo test --workspace` replays it
# (the `fuzz_regressions` module of tests/integration/) until it passes.
#
# Works on a stable toolchain: cargo-fuzz passes nightly-only flags (-Z sanitizer,
# -C passes=sancov-module), so RUSTC_BOOTSTRAP=1 is set for the build.
#
# Environment:
#   FUZZ_TOOLCHAIN   rustup toolchain for the build (default: the active one)
#   FUZZ_SANITIZER   address (default) or none
#   FUZZ_TARGET_DIR  cargo target dir of the fuzz build (default: target/fuzzing)
#   FUZZ_WORK_DIR    scratch folder for seeds, corpora, logs (default: a new temp folder;
#                    name one to keep the corpus between runs)
#   FUZZ_JOBS        targets fuzzed at the same time (default 1)
#   FUZZ_ARGS        extra libFuzzer flags
#   FUZZ_RUN_UNTIL   a time (seconds since the epoch) the whole run must end by, for CI: the
#                    build gets what is left after reserving SECONDS_PER_TARGET for every
#                    target and is stopped if it needs more (exit 3, nothing fuzzed); time it
#                    leaves over lengthens each target's run (never below SECONDS_PER_TARGET)
set -euo pipefail

cd "$(dirname "$0")/.."
root=$PWD
secs=${1:-60}
[ $# -gt 0 ] && shift
case $secs in '' | *[!0-9]*)
    echo "usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]" >&2
    exit 2
    ;;
esac

all=()
for f in fuzz/fuzz_targets/*.rs; do
    all+=("$(basename "$f" .rs)")
done
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${all[@]}")
for t in "${targets[@]}"; do
    if [ ! -f "fuzz/fuzz_targets/$t.rs" ]; then
        echo "unknown fuzz target '$t' (targets: ${all[*]})" >&2
        exit 2
    fi
done

cargo=(cargo)
[ -n "${FUZZ_TOOLCHAIN:-}" ] && cargo=(cargo "+$FUZZ_TOOLCHAIN")
sanitizer=${FUZZ_SANITIZER:-address}
target_dir=${FUZZ_TARGET_DIR:-$root/target/fuzzing}
work=${FUZZ_WORK_DIR:-$(mktemp -d "${TMPDIR:-/tmp}/armhil-fuzz.XXXXXX")}
mkdir -p "$work"
echo "fuzz: ${#targets[@]} target(s), ${secs}s each, sanitizer $sanitizer, scratch $work"

# Seeds: the fixtures and scenarios in each target's input encoding.
"${cargo[@]}" run --quiet -p armhil-testkit --example fuzz_seeds -- "$work/seeds" "${targets[@]}"

# One build for all targets. Release with debug assertions: integer overflow panics, so a
# value that would wrap is a crash.
fuzz_flags=(--fuzz-dir fuzz --target-dir "$target_dir" --release --debug-assertions
    --sanitizer "$sanitizer")
export RUSTC_BOOTSTRAP=1
build_start=$(date +%s)
jobs=${FUZZ_JOBS:-1}
# Targets run FUZZ_JOBS at a time: this many rounds, plus a minute for seeds and reports.
rounds=$(((${#targets[@]} + jobs - 1) / jobs))
# build CARGO_FUZZ_BUILD_ARGS...: one cargo-fuzz build, stopped where FUZZ_RUN_UNTIL leaves
# only the runs' own time.
build() {
    if [ -z "${FUZZ_RUN_UNTIL:-}" ]; then
        "${cargo[@]}" fuzz build "${fuzz_flags[@]}" "$@"
        return
    fi
    local left=$((FUZZ_RUN_UNTIL - rounds * secs - 60 - $(date +%s)))
    [ $left -gt 0 ] || return 124
    timeout "$left" "${cargo[@]}" fuzz build "${fuzz_flags[@]}" "$@"
}
build_status=0
if [ ${#targets[@]} -eq ${#all[@]} ]; then
    build || build_status=$?
else
    for t in "${targets[@]}"; do build "$t" || { build_status=$?; break; }; done
fi
if [ $build_status -eq 124 ]; then
    echo "fuzz: build did not finish in the time FUZZ_RUN_UNTIL leaves; nothing fuzzed" >&2
    exit 3
elif [ $build_status -ne 0 ]; then
    echo "fuzz: build failed (exit $build_status)" >&2
    exit $build_status
fi
echo "fuzz: build took $(($(date +%s) - build_start)) s"

# Stretch the runs over the time left before FUZZ_RUN_UNTIL, so a fast build leaves the
# fuzzers more time, not CI idle.
if [ -n "${FUZZ_RUN_UNTIL:-}" ]; then
    stretched=$(((FUZZ_RUN_UNTIL - $(date +%s) - 60) / rounds))
    if [ "$stretched" -gt "$secs" ]; then
        secs=$stretched
        echo "fuzz: the time left allows ${secs}s per target"
    fi
fi

final_stat() { # final_stat NAME LOG: a final libFuzzer statistic
    sed -n "s/^stat::$1: *//p" "$2" | tail -n 1
}

# run_target NAME: fuzz one target; writes its summary line to $work/NAME.result.
run_target() {
    local t=$1 corpus=$work/corpus/$1 artifacts=$work/artifacts/$1 log=$work/$1.log
    mkdir -p "$corpus" "$artifacts"
    echo "fuzz: running $t for ${secs}s (log $log)"
    local status=0
    # shellcheck disable=SC2086 # FUZZ_ARGS is a list of flags
    "${cargo[@]}" fuzz run "${fuzz_flags[@]}" "$t" "$corpus" "$work/seeds/$t" -- \
        -max_total_time="$secs" -print_final_stats=1 -artifact_prefix="$artifacts/" \
        -max_len=8192 -timeout=30 -rss_limit_mb=4096 ${FUZZ_ARGS:-} >"$log" 2>&1 || status=$?
    local execs rate cov ft verdict=ok
    execs=$(final_stat number_of_executed_units "$log")
    rate=$(final_stat average_exec_per_sec "$log")
    cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    ft=$(grep -o 'ft: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    if [ $status -ne 0 ]; then
        verdict="CRASH (exit $status)"
        mkdir -p "fuzz/regressions/$t"
        for a in "$artifacts"/*; do
            [ -f "$a" ] || continue
            cp "$a" "fuzz/regressions/$t/"
            echo "fuzz: $t: kept $(basename "$a") in fuzz/regressions/$t/"
        done
        tail -n 40 "$log"
    fi
    printf '%-24s %12s %8s %7s %7s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "${cov:-?}" \
        "${ft:-?}" "$verdict" >"$work/$t.result"
}

# FUZZ_JOBS targets at a time (one process each).
running=0
for t in "${targets[@]}"; do
    if [ "$running" -ge "$jobs" ]; then
        wait -n || true
        running=$((running - 1))
    fi
    run_target "$t" &
    running=$((running + 1))
done
wait

printf '\n%-24s %12s %8s %7s %7s  %s\n' target executions exec/s cov ft result
failed=()
for t in "${targets[@]}"; do
    cat "$work/$t.result"
    grep -q CRASH "$work/$t.result" && failed+=("$t")
done
if [ ${#failed[@]} -gt 0 ]; then
    echo "fuzz: crashed: ${failed[*]} (inputs kept in fuzz/regressions/; replay with" \
        "cargo test --test integration fuzz_regressions)" >&2
    exit 1
fi
