#!/usr/bin/env bash
# Run the vcan end-to-end suite: the `#[ignore]`d tests of the `vcan_e2e` test binary, then every
# hook in scripts/e2e/ (*.sh run with bash, *.py with the host's python3), all on a live vcan
# interface.
#
# Where the kernel has vcan (a normal Linux box, `sudo modprobe vcan`), the suite runs directly.
# Our development and CI machines run a kernel without CAN, so there the suite runs inside a
# virtme-ng VM (TCG; KVM hangs on these machines) booting the Debian kernel from /boot, which
# shares the host's filesystem and so runs the host-built binaries. See docs/vcan.md, "Machines
# without kernel CAN".
#
# Environment knobs (all optional):
#   ARMHIL_E2E_MODE       auto (default) | direct | vm
#   ARMHIL_VCAN_IFACE     interface name (default vcan0)
#   ARMHIL_VM_KERNEL      kernel image for the VM (default: newest /boot/vmlinuz-* with vcan.ko)
#   ARMHIL_VM_TIMEOUT_S   hard limit for the whole VM run, boot included (default 1200)
#   ARMHIL_E2E_TEST_TIMEOUT_S / ARMHIL_E2E_HOOK_TIMEOUT_S  passed to the inner runner
#   ARMHIL_E2E_FILTER     test name filter passed to the test binary (default: all)
#   ARMHIL_E2E_MAX_CATCH_UP_MS  `armhil sim piper --max-catch-up-ms` for the scenarios (default
#                         5; empty: none, only the emulator's CPU budget bounds catch-up)
#   ARMHIL_E2E_HOOKS      folder of hook scripts (default scripts/e2e)
#   ARMHIL_REALTIME_PRIORITY  passed on to the emulators (1: deadline-thread pacing)
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo"

mode=${ARMHIL_E2E_MODE:-auto}
iface=${ARMHIL_VCAN_IFACE:-vcan0}
vm_timeout_s=${ARMHIL_VM_TIMEOUT_S:-1200}

log() { printf '[vcan-e2e] %s\n' "$*"; }
die() { printf '[vcan-e2e] ERROR: %s\n' "$*" >&2; exit 1; }

command -v python3 >/dev/null || die "python3 is needed (JSON parsing, python hooks)"

# Prints the `executable` of the compiler artifact named $1 with kind $2 from cargo's JSON
# messages on stdin; compile errors go to stderr.
artifact() {
    python3 -c '
import json, sys
name, kind = sys.argv[1], sys.argv[2]
found = ""
for line in sys.stdin:
    try:
        msg = json.loads(line)
    except ValueError:
        continue
    if msg.get("reason") == "compiler-message" and msg["message"].get("level") == "error":
        sys.stderr.write(msg["message"].get("rendered") or "")
    target = msg.get("target") or {}
    if msg.get("reason") == "compiler-artifact" and msg.get("executable") \
            and target.get("name") == name and kind in target.get("kind", []):
        found = msg["executable"]
print(found)
' "$1" "$2"
}

log "building armhil and the vcan_e2e test binary on the host"
armhil_bin=$(cargo build --bin armhil --message-format=json | artifact armhil bin)
test_bin=$(cargo test --test vcan_e2e --no-run --message-format=json | artifact vcan_e2e test)
[[ -x "$armhil_bin" ]] || die "armhil binary not found after build"
[[ -x "$test_bin" ]] || die "vcan_e2e test binary not found after build"
log "armhil:   $armhil_bin"
log "vcan_e2e: $test_bin"

target_dir=$(cargo metadata --format-version 1 --no-deps |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
# The one directory the VM may write to: the status file, the guest log, test artifacts.
# One per run, so that runs started at the same time by different people do not collide;
# runs older than two hours are pruned.
mkdir -p "$target_dir/vcan-e2e"
find "$target_dir/vcan-e2e" -mindepth 1 -maxdepth 1 -name 'run.*' -mmin +120 -exec rm -rf {} +
run_dir=$(mktemp -d "$target_dir/vcan-e2e/run.XXXXXX")
chmod 755 "$run_dir"
log "run directory: $run_dir"

# The interpreter for python hooks, resolved to a real path: the VM's PATH lacks pyenv and
# similar shims (and a pyenv shim costs ~30 s under TCG anyway).
python_bin=$(python3 -c 'import sys; print(sys.executable)')

inner_env=(
    "ARMHIL_VCAN_IFACE=$iface"
    "ARMHIL_BIN=$armhil_bin"
    "ARMHIL_E2E_TEST_BIN=$test_bin"
    "ARMHIL_E2E_OUT=$run_dir"
    "ARMHIL_E2E_HOOKS=${ARMHIL_E2E_HOOKS:-$repo/scripts/e2e}"
    "ARMHIL_E2E_PYTHON=$python_bin"
    "ARMHIL_E2E_FILTER=${ARMHIL_E2E_FILTER:-}"
    "ARMHIL_E2E_MAX_CATCH_UP_MS=${ARMHIL_E2E_MAX_CATCH_UP_MS-5}"
    "ARMHIL_E2E_TEST_TIMEOUT_S=${ARMHIL_E2E_TEST_TIMEOUT_S:-600}"
    "ARMHIL_E2E_HOOK_TIMEOUT_S=${ARMHIL_E2E_HOOK_TIMEOUT_S:-300}"
    "RUST_BACKTRACE=1"
    # Real-time pacing of the emulators under test (sim::pacer), off unless asked for.
    "ARMHIL_REALTIME_PRIORITY=${ARMHIL_REALTIME_PRIORITY:-}"
)
inner="$repo/scripts/vcan-e2e-inner.sh"

# True when vcan can be used on this kernel without a VM.
vcan_usable_here() {
    ip link show "$iface" >/dev/null 2>&1 && return 0
    [[ $(id -u) -eq 0 ]] || return 1
    modprobe vcan 2>/dev/null || return 1
    ip link add dev "$iface" type vcan 2>/dev/null && ip link set up "$iface"
}

if [[ $mode == auto ]]; then
    if vcan_usable_here; then mode=direct; else mode=vm; fi
fi

summarise() {
    local status_file="$run_dir/status" guest_log=$1
    log "---- summary ($mode) ----"
    grep -E '^(guest kernel|host kernel):|^test result:|^(hook|suite) ' "$guest_log" || true
    [[ -f $status_file ]] || die "no status file: the suite did not finish (timeout or crash)"
    local status
    status=$(<"$status_file")
    [[ $status == 0 ]] || die "vcan e2e suite failed (status $status)"
    log "vcan e2e suite passed"
}

if [[ $mode == direct ]]; then
    log "vcan usable on this kernel: running the suite directly on $iface"
    env "${inner_env[@]}" ARMHIL_E2E_WHERE=host bash "$inner" 2>&1 | tee "$run_dir/guest.log" || true
    summarise "$run_dir/guest.log"
    exit 0
fi

[[ $mode == vm ]] || die "ARMHIL_E2E_MODE must be auto, direct or vm (got $mode)"
command -v vng >/dev/null || die "vng (pip install virtme-ng) is needed to run vcan in a VM"

kernel=${ARMHIL_VM_KERNEL:-}
if [[ -z $kernel ]]; then
    # Newest installed kernel whose modules include vcan.
    for image in $(ls /boot/vmlinuz-* 2>/dev/null | sort -rV); do
        version=${image#/boot/vmlinuz-}
        if find "/lib/modules/$version" -name 'vcan.ko*' 2>/dev/null | grep -q .; then
            kernel=$image
            break
        fi
    done
fi
[[ -n $kernel && -r $kernel ]] ||
    die "no kernel with vcan under /boot (apt-get install linux-image-amd64)"

# vng shares / read-only; only $run_dir is writable. The guest writes its whole output to
# guest.log there (the VM console mangles long output) and its exit status to `status`, which
# is the verdict: vng does not reliably pass the guest's exit code on.
exec_cmd="env"
for kv in "${inner_env[@]}" "ARMHIL_E2E_WHERE=guest"; do exec_cmd+=" $(printf '%q' "$kv")"; done
exec_cmd+=" bash $(printf '%q' "$inner") > $(printf '%q' "$run_dir/guest.log") 2>&1"

log "kernel has no vcan: booting $kernel in a VM (TCG, timeout ${vm_timeout_s}s)"
: >"$run_dir/guest.log"
vm_start=$(date +%s)
timeout --kill-after=30 "$vm_timeout_s" \
    vng --disable-kvm --run "$kernel" --user root --cpus 2 --memory 2G \
    --rwdir "$run_dir" --cwd "$run_dir" --exec "$exec_cmd" \
    </dev/null >"$run_dir/vng.log" 2>&1 &
vng_pid=$!
# Stream the guest's log while it runs.
tail -n +1 -F --pid="$vng_pid" "$run_dir/guest.log" 2>/dev/null &
tail_pid=$!
vng_rc=0
wait "$vng_pid" || vng_rc=$?
wait "$tail_pid" || true
log "VM exited with code $vng_rc after $(( $(date +%s) - vm_start ))s"
if [[ ! -f $run_dir/status ]]; then
    log "last lines of the VM console:"
    tail -n 40 "$run_dir/vng.log" || true
fi
summarise "$run_dir/guest.log"
