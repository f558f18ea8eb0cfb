"""Issue 20 item 1 through the vendor SDK (piper_sdk 0.6.2, unchanged) over socketcand: fold
the arm in position mode with J2 and J3 on their stops, disable, enable again while the wrist
is still sinking, switch to MIT and stream 0x15A-0x15F every 5 ms. Every joint reaches its
target within 0.05 rad and 0x2A1 never reports a collision, with collision protection at its
most sensitive level.

Before the fix the re-enabled, still-sinking wrist latched status 0x07 and the firmware then
refused every MIT frame: no joint moved.

Run (after `cargo build -p armhil`):

    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_piper_mit_friction.py
"""

import json
import os
import time

import pytest

from armhil_process import free_port, listening

if os.environ.get("CI"):
    import can  # noqa: F401  (python-can's socketcand interface is what the SDK opens)
    import piper_sdk  # noqa: F401
else:
    pytest.importorskip("can")
    pytest.importorskip("piper_sdk")

FIRMWARE = "S-V1.8-2"
FOLD_RAD = [0.2, 0.0, 0.0, 0.2, 0.4, 0.3]
TARGET_RAD = [0.5, 0.0, 0.0, 0.2, 0.4, 0.6]
KP = [10.0, 10.0, 10.0, 10.0, 40.0, 10.0]
KD = 0.8
TOLERANCE_RAD = 0.05
COLLISION = 0x07
MDEG_PER_RAD = 180_000.0 / 3.141592653589793


@pytest.fixture(scope="module")
def piper():
    port = free_port()
    args = ["sim", "piper", "--socketcand", f"127.0.0.1:{port}", "--firmware", FIRMWARE]
    with listening(args, port) as proc:
        os.environ["CAN_CONFIG"] = json.dumps({"host": "127.0.0.1", "port": port})
        from piper_sdk import C_PiperInterface_V2

        # A CAN name of its own: the SDK keeps one instance per name.
        arm = C_PiperInterface_V2(can_name="can_mit", judge_flag=False, can_auto_init=False)
        arm.CreateCanBus("can_mit", bustype="socketcand")
        arm.ConnectPort()
        try:
            yield arm
        finally:
            arm.DisconnectPort()
            os.environ.pop("CAN_CONFIG", None)
    assert proc.returncode == 0, f"emulator exit {proc.returncode}: {proc.stderr_tail}"


def as_int(value):
    return int(getattr(value, "value", value))


def joints_rad(arm):
    js = arm.GetArmJointMsgs().joint_state
    mdeg = [js.joint_1, js.joint_2, js.joint_3, js.joint_4, js.joint_5, js.joint_6]
    return [m / MDEG_PER_RAD for m in mdeg]


def wait_for(predicate, timeout_s, what, poll_s=0.02):
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(poll_s)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what} (last: {last!r})")


class StatusWatch:
    """Every 0x2A1 arm status the client looked at."""

    def __init__(self, arm):
        self.arm = arm
        self.seen = []

    def read(self):
        status = as_int(self.arm.GetArmStatus().arm_status.arm_status)
        self.seen.append(status)
        return status

    def collided(self):
        return COLLISION in self.seen


def test_mit_after_a_fold_at_the_stops_and_a_quick_re_enable(piper):
    arm = piper
    watch = StatusWatch(arm)
    wait_for(lambda: arm.GetArmStatus().time_stamp > 0, 10, "0x2A1 status feedback")
    # The most sensitive collision protection on every joint.
    arm.CrashProtectionConfig(8, 8, 8, 8, 8, 8)
    time.sleep(0.1)

    # Fold in position mode (MOVE J): J2 and J3 stay on their stops at 0.
    wait_for(arm.EnablePiper, 10, "all six joints enabled", poll_s=0.05)
    target_mdeg = [round(r * MDEG_PER_RAD) for r in FOLD_RAD]

    def folded():
        arm.ModeCtrl(0x01, 0x01, 100, 0x00)
        arm.JointCtrl(*target_mdeg)
        watch.read()
        return max(abs(a - b) for a, b in zip(joints_rad(arm), FOLD_RAD)) < 0.01

    wait_for(folded, 10, f"the fold {FOLD_RAD}", poll_s=0.05)

    # Disable; the wrist starts to sink. Enable again 0.3 s later, while it still falls.
    wait_for(lambda: not arm.DisablePiper(), 5, "all joints disabled", poll_s=0.02)
    time.sleep(0.3)
    wait_for(arm.EnablePiper, 10, "all six joints enabled again", poll_s=0.02)
    arm.ModeCtrl(0x01, 0x04, 0x64, 0xAD)

    started = time.monotonic()
    reached_s = None
    while time.monotonic() - started < 8.0:
        for j in range(6):
            arm.JointMitCtrl(j + 1, TARGET_RAD[j], 0.0, KP[j], KD, 0.0)
        watch.read()
        err = max(abs(a - b) for a, b in zip(joints_rad(arm), TARGET_RAD))
        if err < TOLERANCE_RAD:
            reached_s = reached_s or time.monotonic() - started
            if time.monotonic() - started - reached_s > 1.0:
                break
        else:
            reached_s = None
        time.sleep(0.005)

    q = joints_rad(arm)
    print(f"MIT target within {TOLERANCE_RAD} rad after {reached_s} s; joints {q}")
    # The emulator runs in real time and the client's 5 ms loop in Python is slower than the
    # firmware test's: the 3 s deadline is checked there (sim/tests/piper/mit_friction.rs);
    # here the target must be reached and held.
    assert reached_s is not None, f"MIT target {TARGET_RAD} not reached: joints {q}"
    assert reached_s < 5.0, f"reached after {reached_s:.2f} s"
    assert not watch.collided(), f"0x2A1 said collision (statuses seen: {sorted(set(watch.seen))})"

    wait_for(lambda: not arm.DisablePiper(), 5, "all joints disabled", poll_s=0.02)
    time.sleep(0.1)
    assert watch.read() == 0x00, "arm status after disabling"
