#!/usr/bin/env bash
# LeRobot's OpenArm follower (lerobot 0.6.1, unchanged) against `armhil sim robot
# robots/openarm.yaml`: tests/sdk/test_lerobot_openarm.py in a Python 3.12 venv of its own
# (lerobot 0.5 and later need 3.12; the suite's own python3 is 3.11 and skips that file).
#
#   scripts/ci/lerobot.sh install   make the venv (about 3 GB of wheels: torch is imported by
#                                   lerobot's modules at load time; see the test's docstring)
#   scripts/ci/lerobot.sh test      run the test file with ARMHIL_BIN (default target/debug/armhil)
#
# Environment: ARMHIL_LEROBOT_VENV (default /tmp/armhil-lerobot-venv). A machine without a
# Python 3.12 (pyenv's or on PATH) prints why and exits 0 from both: it cannot be installed from
# the registries these machines reach.
set -euo pipefail

venv=${ARMHIL_LEROBOT_VENV:-/tmp/armhil-lerobot-venv}
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

find_python312() {
    local candidate
    for candidate in "$(command -v python3.12 2>/dev/null || true)" \
        $(ls -d "$(pyenv root 2>/dev/null || echo /nonexistent)"/versions/3.12*/bin/python3 2>/dev/null | sort -V); do
        [[ -n $candidate && -x $candidate ]] && echo "$candidate"
    done | tail -n 1
}

case ${1:-} in
install)
    py=$(find_python312)
    if [[ -z $py ]]; then
        echo "lerobot: SKIPPED, no Python 3.12 on this machine (lerobot 0.6.1 needs it)"
        exit 0
    fi
    start=$(date +%s)
    "$py" -m venv "$venv"
    # The dependencies first and lerobot last without its own (it would pull in torchvision,
    # OpenCV, gymnasium, … that the follower never imports); --no-compile: byte-compiling torch
    # would take minutes.
    "$venv/bin/pip" install -q --no-compile torch==2.11.0 numpy==2.2.6 draccus==0.11.6 \
        huggingface-hub==1.33.0 tqdm==4.70.1 python-can==4.6.1 pytest==8.3.4
    "$venv/bin/pip" install -q --no-compile --no-deps lerobot==0.6.1
    echo "lerobot: venv $venv ready in $(( $(date +%s) - start ))s"
    ;;
test)
    if [[ ! -x $venv/bin/python ]]; then
        if [[ -z $(find_python312) ]]; then
            echo "lerobot: SKIPPED, no Python 3.12 on this machine (lerobot 0.6.1 needs it)"
            exit 0
        fi
        echo "lerobot: no venv at $venv (run: $0 install)" >&2
        exit 1
    fi
    cd "$repo"
    CI=${CI:-} ARMHIL_BIN=${ARMHIL_BIN:-$repo/target/debug/armhil} \
        "$venv/bin/python" -m pytest -q -p no:cacheprovider tests/sdk/test_lerobot_openarm.py
    ;;
*)
    echo "usage: $0 install|test" >&2
    exit 2
    ;;
esac
