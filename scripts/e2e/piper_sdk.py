#!/usr/bin/env python3
"""vcan end-to-end hook: the vendor Python SDK (piper_sdk) against `armhil sim piper`.

The SDK runs unchanged, as a user runs it, on one end of a vxcan pair ($ARMHIL_VXCAN_SDK,
`vxcan0`) and the emulator on the other: starts `$ARMHIL_BIN sim piper --iface
$ARMHIL_VXCAN_SIM --firmware S-V1.8-2` (unless ARMHIL_PIPER_EXTERNAL=1, then an emulator must
already run on the peer), then with `C_PiperInterface_V2(iface, judge_flag=False)` (a virtual
interface has no bitrate for the SDK to check; `judge_flag` is the SDK's own option for that).
A plain vcan would not do: the SDK sends on a socket with CAN_RAW_LOOPBACK off, and a vcan
delivers such frames to nobody; a vxcan hands them to its peer.

1. connects (the SDK queries limits, max acc and the firmware version) and checks the
   firmware string and the 0x473 joint limits (with a kernel filter on the SDK's receive
   socket for that step, so that the slow VM's queue overflow cannot eat the 0x4AF burst);
2. enables the arm, selects CAN mode + MOVE J at 50 %, moves to a joint target and reads the
   joints back within 0.1 deg;
3. opens the gripper to 40 mm and reads the stroke back within 1 mm;
4. checks that piper_sdk's own forward kinematics of the reported joints agrees with the
   emulator's end-pose feedback (0x2A2-0x2A4) within 0.5 mm / 0.5 deg;
5. disables the arm.

Exits non-zero with a message saying which step failed. Timeouts are generous: inside the CI
VM (TCG) everything runs several times slower.
"""

import os
import signal
import subprocess
import sys
import time

SDK_IFACE = os.environ.get("ARMHIL_VXCAN_SDK", "vxcan0")
SIM_IFACE = os.environ.get("ARMHIL_VXCAN_SIM", "vxcan1")
ARMHIL_BIN = os.environ.get("ARMHIL_BIN", "armhil")
EXTERNAL = os.environ.get("ARMHIL_PIPER_EXTERNAL") == "1"
OUT_DIR = os.environ.get("ARMHIL_E2E_OUT", "/tmp")
FIRMWARE = "S-V1.8-2"
# Spec §6.4 defaults the emulator's flash starts with (0.1 deg, 0.01 rad/s).
EXPECTED_LIMITS = {
    1: (1500, -1500),
    2: (1800, 0),
    3: (0, -1700),
    4: (890, -890),
    5: (890, -890),
    6: (1800, -1800),
}
TARGET_MDEG = [20000, 40000, -40000, 10000, 20000, -15000]
GRIPPER_UM = 40000


T0 = time.monotonic()


def say(msg):
    """Progress line with the seconds since the hook started (the VM is slow: show where)."""
    print(f"[{time.monotonic() - T0:6.1f} s] {msg}", flush=True)


class Failure(Exception):
    """A check failed; the message says which."""


def as_int(value):
    """piper_sdk decodes status bytes into enums; compare their numeric value."""
    return int(getattr(value, "value", value))


def wait_for(predicate, timeout_s, what, poll_s=0.02):
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(poll_s)
    raise Failure(f"timed out after {timeout_s:.0f} s waiting for {what} (last: {last!r})")


def joints_mdeg(piper):
    js = piper.GetArmJointMsgs().joint_state
    return [js.joint_1, js.joint_2, js.joint_3, js.joint_4, js.joint_5, js.joint_6]


def sdk_buses(piper):
    """The python-can buses the SDK receives and sends on (0.6.2 opens two on Linux)."""
    port = piper.GetCanBus()
    rx = getattr(port, "recv_bus", None) or getattr(port, "bus", None)
    tx = getattr(port, "send_bus", None) or rx
    if rx is None or tx is None:
        raise Failure(f"cannot find the SDK's CAN sockets on {type(port).__name__}")
    return rx, tx


def check_firmware_and_limits(piper):
    """Step 1 (see run_checks): the 0x4AF version string and the 0x473 limits."""
    # The SDK clears its firmware buffer right after sending the query (SearchPiperFirmware-
    # Version) and returns the 8 bytes after "S-V" as soon as "S-V" is in the buffer, so a
    # reply read half-way gives "S-V1": wait for the whole string, re-query when none comes.
    def firmware():
        version = piper.GetPiperFirmwareVersion()
        return version if isinstance(version, str) and len(version) >= len(FIRMWARE) else None

    version = None
    for attempt in range(1, 7):
        piper.SearchPiperFirmwareVersion()
        try:
            version = wait_for(firmware, 10, "the 0x4AF firmware reply")
            break
        except Failure as e:
            say(f"firmware query {attempt}: {e}")
    if version != FIRMWARE:
        raise Failure(f"firmware version {version!r}, expected {FIRMWARE!r}")
    say(f"firmware {version}")

    # GetAllMotorAngleLimitMaxSpd() is unusable here: piper_sdk 0.6.x stores a reference to
    # its one reused rx message object in all six slots, so after the connect burst every slot
    # shows joint 6. Query joint by joint and read the per-reply copy instead.
    for n, (max_ddeg, min_ddeg) in EXPECTED_LIMITS.items():
        def reply_for_n(n=n):
            cur = piper.GetCurrentMotorAngleLimitMaxVel().current_motor_angle_limit_max_vel
            if cur.motor_num != n:
                piper.SearchMotorMaxAngleSpdAccLimit(n, 0x01)
                return None
            return (cur.max_angle_limit, cur.min_angle_limit, cur.max_joint_spd)

        piper.SearchMotorMaxAngleSpdAccLimit(n, 0x01)
        got = wait_for(reply_for_n, 20, f"the 0x473 reply for joint {n}", poll_s=0.1)
        if got != (max_ddeg, min_ddeg, 300):
            raise Failure(f"joint {n} limits {got}, expected {(max_ddeg, min_ddeg, 300)}")
    say("joint limits match the flash defaults")


def run_checks():
    from piper_sdk import C_PiperInterface_V2

    say("piper_sdk imported")
    piper = C_PiperInterface_V2(SDK_IFACE, judge_flag=False)
    sdk_rx, _sdk_tx = sdk_buses(piper)
    piper.ConnectPort()

    wait_for(lambda: piper.GetArmStatus().time_stamp > 0, 30, "0x2A1 status feedback")
    say("connected; feedback flowing")

    # 1. Firmware version and joint limits. The arm streams ~3000 feedback frames/s; under TCG
    #    the SDK's reader thread parses only a few hundred per second, so its socket queue
    #    overflows and the kernel drops most frames, and with them the 11-frame 0x4AF burst
    #    (the SDK needs the two frames holding "S-V1" and ".8-2" back to back). Let the kernel
    #    queue only the replies of this step on the SDK's own socket (python-can filters, i.e.
    #    CAN_RAW_FILTER) and lift the filter afterwards. The SDK itself parses the replies.
    sdk_rx.set_filters([
        {"can_id": 0x4AF, "can_mask": 0x7FF},
        {"can_id": 0x473, "can_mask": 0x7FF},
    ])
    try:
        check_firmware_and_limits(piper)
    finally:
        sdk_rx.set_filters(None)

    # 2. Enable (the SDK demo loop: EnablePiper returns the state read before sending).
    wait_for(piper.EnablePiper, 20, "all six joints enabled (0x261-0x266 bit 6)", poll_s=0.05)
    piper.ModeCtrl(0x01, 0x01, 50, 0x00)

    def in_move_j():
        s = piper.GetArmStatus().arm_status
        return as_int(s.ctrl_mode) == 0x01 and as_int(s.mode_feed) == 0x01 and as_int(s.arm_status) == 0

    wait_for(in_move_j, 10, "0x2A1 showing CAN mode + MOVE J + normal")
    say("enabled, CAN mode, MOVE J")

    deadline = time.monotonic() + 60
    while True:
        piper.ModeCtrl(0x01, 0x01, 50, 0x00)
        piper.JointCtrl(*TARGET_MDEG)
        time.sleep(0.05)
        status = piper.GetArmStatus().arm_status
        if as_int(status.arm_status) != 0:
            raise Failure(f"arm_status {as_int(status.arm_status):#04x} during MOVE J")
        err = max(abs(a - b) for a, b in zip(joints_mdeg(piper), TARGET_MDEG))
        if as_int(status.motion_status) == 0 and err <= 100:
            break
        if time.monotonic() > deadline:
            raise Failure(f"MOVE J did not arrive: joints {joints_mdeg(piper)}, target {TARGET_MDEG}")
    time.sleep(0.3)
    joints = joints_mdeg(piper)
    err = max(abs(a - b) for a, b in zip(joints, TARGET_MDEG))
    if err > 100:
        raise Failure(f"joints {joints} differ from target {TARGET_MDEG} by {err} m° (> 0.1°)")
    say(f"MOVE J arrived, max error {err} m°")

    # 3. Gripper.
    def gripper_there():
        piper.GripperCtrl(GRIPPER_UM, 1000, 0x01, 0)
        stroke = piper.GetArmGripperMsgs().gripper_state.grippers_angle
        return abs(stroke - GRIPPER_UM) <= 1000 and stroke

    stroke = wait_for(gripper_there, 30, f"gripper stroke {GRIPPER_UM} µm", poll_s=0.05)
    say(f"gripper at {stroke} µm")

    # 4. The SDK's forward kinematics against our end-pose feedback.
    piper.EnableFkCal()
    time.sleep(0.5)
    fk = piper.GetFK("feedback")[5]
    pose = piper.GetArmEndPoseMsgs().end_pose
    fb = [pose.X_axis / 1000, pose.Y_axis / 1000, pose.Z_axis / 1000,
          pose.RX_axis / 1000, pose.RY_axis / 1000, pose.RZ_axis / 1000]
    for i, name in enumerate(["X", "Y", "Z"]):
        if abs(fk[i] - fb[i]) > 0.5:
            raise Failure(f"end pose {name}: SDK FK {fk[i]:.3f} mm, feedback {fb[i]:.3f} mm")
    for i, name in zip(range(3, 6), ["RX", "RY", "RZ"]):
        diff = (fk[i] - fb[i] + 180.0) % 360.0 - 180.0
        if abs(diff) > 0.5:
            raise Failure(f"end pose {name}: SDK FK {fk[i]:.3f}°, feedback {fb[i]:.3f}°")
    say(f"SDK FK agrees with end-pose feedback: {[round(x, 2) for x in fb]}")

    # 5. Disable. In the emulated (TCG) test VM, where the Piper runs at about a quarter of
    # real time (its log: 1 ms steps cost 3.4-6.6 ms, three steps in four dropped), the SDK
    # has seen every joint disabled 12 to 18 s after its first request in earlier runs, 49 s
    # and over 60 s in two runs on 2026-12-07, although the firmware disables at once and
    # sends the 0x261-0x266 status at 9 Hz there: the SDK's view lags (an open finding,
    # docs/timing.md). 150 s keeps the check (it fails if the arm never reads disabled)
    # without failing on that VM's pace.
    wait_for(lambda: not piper.DisablePiper(), 150, "all joints disabled", poll_s=0.05)
    say("disabled")
    piper.DisconnectPort()


def main():
    child = None
    log = None
    if not EXTERNAL:
        log_path = os.path.join(OUT_DIR, "piper_sdk_emulator.log")
        log = open(log_path, "w")
        cmd = [ARMHIL_BIN, "sim", "piper", "--iface", SIM_IFACE, "--firmware", FIRMWARE]
        print("starting", " ".join(cmd), "(log:", log_path + ")")
        child = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        time.sleep(1.0)
        if child.poll() is not None:
            print(f"piper_sdk e2e FAILED: emulator exited with {child.returncode}, see {log_path}",
                  file=sys.stderr)
            return 1
    try:
        run_checks()
    except Failure as e:
        print(f"piper_sdk e2e FAILED: {e}", file=sys.stderr)
        return 1
    finally:
        if child is not None:
            child.send_signal(signal.SIGINT)
            try:
                child.wait(timeout=20)
                say(f"emulator stopped (exit {child.returncode})")
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()
                say("emulator did not stop on SIGINT within 20 s: killed")
        if log is not None:
            log.close()
    print("piper_sdk e2e OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
