#!/usr/bin/env bash
# The Python package's checks: fmt and clippy of the extension crate (python/ is its own
# cargo workspace, excluded from the root one), a dev-profile wheel built with maturin and
# installed into a venv, then `pytest python/tests` against the in-process emulators.
#
# Usage, from anywhere: bash scripts/ci/python.sh
# Needs Rust (cargo, rustfmt, clippy) and CPython >= 3.9 with venv (Debian: python3-venv; the
# script installs it when run as root on Debian and it is missing). Environment:
#   PYTHON            interpreter to build the venv from (default python3)
#   ARMHIL_PY_VENV    venv folder (default target/python-venv, reused across runs)
#   CARGO_TARGET_DIR  shared with the root workspace's builds when set (default target/)
# The benchmark (python/bench/bench_binding.py) wants a release build and is not run here.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
root=$(pwd)
start=$(date +%s)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}
PYTHON=${PYTHON:-python3}
venv=${ARMHIL_PY_VENV:-$root/target/python-venv}
# Pinned build and test tools (pytest and python-can as in .ci/run; python-can is the client
# of the robot tests, python/tests/test_robot.py).
MATURIN_VERSION=1.16.0
PYTEST_VERSION=8.3.4
PYTHON_CAN_VERSION=4.6.1

step() { printf '\n---- %s (%ss)\n' "$*" "$(( $(date +%s) - start ))"; }

step "python venv at $venv"
if [[ ! -x $venv/bin/python ]]; then
    if ! "$PYTHON" -m venv "$venv" 2>/dev/null; then
        # Debian ships venv separately.
        if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
            apt-get install -y -q python3-venv
            rm -rf "$venv"
            "$PYTHON" -m venv "$venv"
        else
            echo "cannot create a venv with $PYTHON (install python3-venv)" >&2
            exit 1
        fi
    fi
fi
"$venv/bin/python" --version
"$venv/bin/python" -m pip install -q --disable-pip-version-check \
    "maturin==$MATURIN_VERSION" "pytest==$PYTEST_VERSION" "python-can==$PYTHON_CAN_VERSION"

step "cargo fmt --check (python/)"
(cd python && cargo fmt --check)

step "cargo clippy (python/)"
(cd python && cargo clippy --all-targets --locked -- -D warnings)

step "maturin build (dev profile) and install the wheel"
wheels=$CARGO_TARGET_DIR/python-wheels
rm -rf "$wheels"
"$venv/bin/maturin" build --manifest-path python/Cargo.toml --profile dev --locked \
    --interpreter "$venv/bin/python" --out "$wheels"
"$venv/bin/python" -m pip install -q --disable-pip-version-check --force-reinstall \
    --no-deps "$wheels"/armhil-*.whl
# The wheel carries the stubs and the pytest plugin entry point.
"$venv/bin/python" - <<'PY'
import importlib.metadata as md, pathlib, armhil
pkg = pathlib.Path(armhil.__file__).parent
assert (pkg / "py.typed").exists() and (pkg / "_armhil.pyi").exists(), "stubs missing"
eps = [e.value for e in md.entry_points(group="pytest11") if e.name == "armhil"]
assert eps == ["armhil.pytest_plugin"], eps
print("installed", armhil.__file__)
PY

step "pytest python/tests"
# From the repository root, pytest puts python/tests (not python/) on sys.path, so
# `import armhil` is the installed wheel, not the source folder.
rc=0
"$venv/bin/python" -m pytest python/tests -p no:cacheprovider -rfE -q || rc=$?
step "done: pytest exit $rc"
exit $rc
