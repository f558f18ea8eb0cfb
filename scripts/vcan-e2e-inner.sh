#!/usr/bin/env bash
# The vcan end-to-end suite proper, run by scripts/vcan-e2e.sh either directly on the host or
# as the command of the VM. Brings up the interface, runs the `#[ignore]`d tests of the vcan_e2e
# binary, then every hook in scripts/e2e/ in name order (*.sh with bash, *.py with python).
# Writes the number of failed parts to $ARMHIL_E2E_OUT/status at the end (0 = passed).
#
# Hook contract: a hook gets ARMHIL_VCAN_IFACE, ARMHIL_BIN (the armhil binary), ARMHIL_E2E_OUT
# (a writable directory) and PYTHON in its environment, runs with the repo root as working
# directory (read-only in the VM: write under ARMHIL_E2E_OUT or /tmp), must finish within
# ARMHIL_E2E_HOOK_TIMEOUT_S seconds and fails the suite by exiting non-zero.
set -uo pipefail

: "${ARMHIL_VCAN_IFACE:?}" "${ARMHIL_BIN:?}" "${ARMHIL_E2E_TEST_BIN:?}" "${ARMHIL_E2E_OUT:?}"
: "${ARMHIL_E2E_HOOKS:?}" "${ARMHIL_E2E_PYTHON:?}"
test_timeout_s=${ARMHIL_E2E_TEST_TIMEOUT_S:-600}
hook_timeout_s=${ARMHIL_E2E_HOOK_TIMEOUT_S:-300}
iface=$ARMHIL_VCAN_IFACE
status_file="$ARMHIL_E2E_OUT/status"
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
rm -f "$status_file"

failures=0
# Whatever happens below, leave a verdict for the host (a missing file means "did not finish").
trap 'echo "$failures" >"$status_file"' EXIT

elapsed() { echo $(( $(date +%s) - $1 ))s; }

echo "${ARMHIL_E2E_WHERE:-host} kernel: $(uname -r)"
echo "uptime at start: $(cut -d' ' -f1 /proc/uptime)s, cpus: $(nproc)"

if ! ip link show "$iface" >/dev/null 2>&1; then
    if ! { modprobe vcan && ip link add dev "$iface" type vcan && ip link set up "$iface"; }; then
        echo "suite FAILED: cannot bring up $iface"
        failures=1
        exit 1
    fi
fi
ip -brief link show "$iface"

# A vxcan pair for the vendor SDK hooks: what one end sends arrives on the other whatever the
# sender's CAN_RAW_LOOPBACK, so an SDK that turns its own loopback off (piper_sdk does) works
# unchanged with the emulator on the peer. A plain vcan delivers such frames to nobody.
vxcan_sdk=${ARMHIL_VXCAN_SDK:-vxcan0}
vxcan_sim=${ARMHIL_VXCAN_SIM:-vxcan1}
if ! ip link show "$vxcan_sdk" >/dev/null 2>&1; then
    if ! { modprobe vxcan && ip link add "$vxcan_sdk" type vxcan peer name "$vxcan_sim" \
            && ip link set up "$vxcan_sdk" && ip link set up "$vxcan_sim"; }; then
        echo "suite FAILED: cannot create the vxcan pair $vxcan_sdk/$vxcan_sim"
        failures=1
        exit 1
    fi
fi
ip -brief link show "$vxcan_sdk"
ip -brief link show "$vxcan_sim"
export ARMHIL_VXCAN_SDK=$vxcan_sdk ARMHIL_VXCAN_SIM=$vxcan_sim

# The Python SDK hooks need the interpreter that has python-can and piper_sdk first on PATH.
PATH="$(dirname "$ARMHIL_E2E_PYTHON"):$PATH"
export PATH PYTHON="$ARMHIL_E2E_PYTHON"
export ARMHIL_VCAN_IFACE ARMHIL_BIN ARMHIL_E2E_OUT
cd "$repo"

echo "==== vcan_e2e tests (--ignored, one thread, timeout ${test_timeout_s}s) ===="
start=$(date +%s)
filter=()
[[ -n ${ARMHIL_E2E_FILTER:-} ]] && filter=("$ARMHIL_E2E_FILTER")
timeout --kill-after=10 "$test_timeout_s" \
    "$ARMHIL_E2E_TEST_BIN" --ignored --test-threads=1 "${filter[@]}"
rc=$?
if [[ $rc -eq 0 ]]; then
    echo "suite vcan_e2e passed in $(elapsed "$start")"
else
    [[ $rc -eq 124 ]] && echo "vcan_e2e timed out after ${test_timeout_s}s"
    echo "suite vcan_e2e FAILED (exit $rc) in $(elapsed "$start")"
    failures=$((failures + 1))
fi

python_safe_path=()
"$ARMHIL_E2E_PYTHON" -P -c '' 2>/dev/null && python_safe_path=(-P)

shopt -s nullglob
hooks=("$ARMHIL_E2E_HOOKS"/*.sh "$ARMHIL_E2E_HOOKS"/*.py)
if ((${#hooks[@]})); then mapfile -t hooks < <(printf '%s\n' "${hooks[@]}" | sort); fi
echo "==== ${#hooks[@]} e2e hook(s) in scripts/e2e ===="
for hook in "${hooks[@]}"; do
    name=$(basename "$hook")
    case $hook in
        # -P: do not put scripts/e2e first on sys.path, where a hook named like a package
        # (piper_sdk.py) would shadow the package it imports (Python 3.11+).
        *.py) runner=("$ARMHIL_E2E_PYTHON" -u "${python_safe_path[@]}") ;;
        *) runner=(bash) ;;
    esac
    echo "---- hook $name ----"
    start=$(date +%s)
    timeout --kill-after=10 "$hook_timeout_s" "${runner[@]}" "$hook"
    rc=$?
    if [[ $rc -eq 0 ]]; then
        echo "hook $name passed in $(elapsed "$start")"
    else
        [[ $rc -eq 124 ]] && echo "hook $name timed out after ${hook_timeout_s}s"
        echo "hook $name FAILED (exit $rc) in $(elapsed "$start")"
        failures=$((failures + 1))
    fi
done

echo "suite finished: $failures failed part(s), uptime $(cut -d' ' -f1 /proc/uptime)s"
[[ $failures -eq 0 ]]
