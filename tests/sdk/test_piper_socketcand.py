"""No kernel CAN needed: python-can's `socketcand` interface and the vendor SDK (piper_sdk 0.6.2,
unchanged) against `armhil sim piper --socketcand`.

Run (after `cargo build -p armhil`):

    pip install python-can==4.6.1 piper_sdk==0.6.2 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_piper_socketcand.py

The emulator is started on a free 127.0.0.1 port for this module and stopped with SIGINT at the
end. piper_sdk is reached through its documented path for other bus types: construct with
`can_auto_init=False`, then `CreateCanBus(name, bustype="socketcand")`; python-can takes the
server's host and port from its configuration (here the CAN_CONFIG environment variable).
"""

import json
import os
import time

import pytest

from armhil_process import free_port, listening

if os.environ.get("CI"):
    # In CI both are installed by .ci/run: a missing package is a failure, not a skip.
    import can
    import piper_sdk
else:
    can = pytest.importorskip("can")
    piper_sdk = pytest.importorskip("piper_sdk")

FIRMWARE = "S-V1.8-2"
TARGET_MDEG = [20000, 40000, -40000, 10000, 20000, -15000]
GRIPPER_UM = 40000


@pytest.fixture(scope="module")
def server():
    """`armhil sim piper --socketcand 127.0.0.1:PORT`; yields (host, port)."""
    port = free_port()
    args = ["sim", "piper", "--socketcand", f"127.0.0.1:{port}", "--firmware", FIRMWARE]
    with listening(args, port) as proc:
        yield ("127.0.0.1", port)
    assert proc.returncode == 0, f"emulator exit {proc.returncode}: {proc.stderr_tail}"


def open_bus(server, channel="can0"):
    host, port = server
    return can.Bus(interface="socketcand", host=host, port=port, channel=channel)


def wait_for(predicate, timeout_s, what, poll_s=0.02):
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(poll_s)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what} (last: {last!r})")


def test_python_can_receives_feedback_and_the_emulator_answers(server):
    bus = open_bus(server)
    try:
        seen = {}
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and len(seen) < 8:
            msg = bus.recv(0.5)
            if msg is not None and 0x2A1 <= msg.arbitration_id <= 0x2A8:
                assert not msg.is_extended_id
                seen[msg.arbitration_id] = msg
        assert sorted(seen) == list(range(0x2A1, 0x2A9)), f"feedback ids {sorted(map(hex, seen))}"
        assert len(seen[0x2A1].data) == 8

        # The firmware-version query (0x4AF, byte 0 = 1) makes the emulator answer with its
        # version string in a burst of 0x4AF frames.
        bus.send(can.Message(arbitration_id=0x4AF, data=[1, 0, 0, 0, 0, 0, 0, 0],
                             is_extended_id=False))
        text = bytearray()
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and FIRMWARE.encode() not in text:
            msg = bus.recv(0.5)
            if msg is not None and msg.arbitration_id == 0x4AF:
                text += msg.data
        assert FIRMWARE.encode() in text, f"0x4AF replies {bytes(text)!r}"
    finally:
        bus.shutdown()


def test_two_python_can_clients_exchange_standard_and_extended_frames(server):
    a = open_bus(server)
    b = open_bus(server, channel="vcan7")  # any bus name opens the one bus
    try:
        time.sleep(0.3)  # past the server's rawmode grace period
        sent = [
            can.Message(arbitration_id=0x123, data=[0x11, 0x22, 0x33], is_extended_id=False),
            can.Message(arbitration_id=0x1ABCDEF0, data=[0xFF] * 8, is_extended_id=True),
            can.Message(arbitration_id=0x7FF, data=[], is_extended_id=False),
            can.Message(arbitration_id=0x00000005, data=[0], is_extended_id=True),
        ]
        for msg in sent:
            a.send(msg)
        got = []
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and len(got) < len(sent):
            msg = b.recv(0.5)
            # Skip the emulator's own traffic (all standard 0x2xx feedback).
            if msg is not None and msg.arbitration_id in {m.arbitration_id for m in sent}:
                got.append(msg)
        assert [(m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in got] == [
            (m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in sent
        ]
        assert all(m.timestamp > 1_600_000_000 for m in got), "timestamps are Unix time"
    finally:
        a.shutdown()
        b.shutdown()


def as_int(value):
    """piper_sdk decodes status bytes into enums; compare their numeric value."""
    return int(getattr(value, "value", value))


def joints_mdeg(piper):
    js = piper.GetArmJointMsgs().joint_state
    return [js.joint_1, js.joint_2, js.joint_3, js.joint_4, js.joint_5, js.joint_6]


def firmware_of(piper):
    """The whole version string once the SDK has it, else None. The SDK clears its buffer
    when it sends the query and reads "S-V" plus 5 characters."""
    version = piper.GetPiperFirmwareVersion()
    return version if isinstance(version, str) and len(version) >= len(FIRMWARE) else None


def test_piper_sdk_firmware_version_right_after_connect(server, monkeypatch):
    """Issue 20 item 4: `ConnectPort()` sends the firmware query and the answer is read
    without asking again, as over a vxcan pair (the vendor's piper_read_firmware.py waits
    30 ms). piper_sdk 0.6.2 on Linux reads on one python-can connection and sends on a
    second one opened right after it: the answer must reach the first, which has sent
    nothing since its handshake."""
    host, port = server
    monkeypatch.setenv("CAN_CONFIG", json.dumps({"host": host, "port": port}))
    from piper_sdk import C_PiperInterface_V2

    # Not the other test's name: the SDK keeps one instance per CAN name. Any name opens
    # the server's one bus.
    piper = C_PiperInterface_V2(can_name="can1", judge_flag=False, can_auto_init=False)
    piper.CreateCanBus("can1", bustype="socketcand")
    piper.ConnectPort()
    try:
        started = time.monotonic()
        version = None
        while version is None and time.monotonic() - started < 3:
            version = firmware_of(piper)
            time.sleep(0.005)
        elapsed = time.monotonic() - started
        # Before the fix: -0x4AF (-1199) for as long as one waited.
        assert version == FIRMWARE, (
            f"GetPiperFirmwareVersion() = {piper.GetPiperFirmwareVersion()!r} "
            f"{elapsed:.3f} s after ConnectPort(), without a second query"
        )
    finally:
        piper.DisconnectPort()


def test_piper_sdk_through_create_can_bus(server, monkeypatch):
    host, port = server
    # python-can's configuration supplies what CreateCanBus cannot pass: host and port.
    monkeypatch.setenv("CAN_CONFIG", json.dumps({"host": host, "port": port}))
    from piper_sdk import C_PiperInterface_V2

    piper = C_PiperInterface_V2(can_name="can0", judge_flag=False, can_auto_init=False)
    piper.CreateCanBus("can0", bustype="socketcand")
    piper.ConnectPort()
    try:
        wait_for(lambda: piper.GetArmStatus().time_stamp > 0, 10, "0x2A1 status feedback")

        # Firmware asked again (the answer to ConnectPort's own query is the test above).
        version = None
        for _ in range(5):
            piper.SearchPiperFirmwareVersion()
            deadline = time.monotonic() + 3
            while time.monotonic() < deadline and version is None:
                version = firmware_of(piper)
                time.sleep(0.02)
            if version:
                break
        assert version == FIRMWARE

        # Enable, CAN mode + MOVE J, move to a joint target.
        wait_for(piper.EnablePiper, 10, "all six joints enabled", poll_s=0.05)
        piper.ModeCtrl(0x01, 0x01, 50, 0x00)
        deadline = time.monotonic() + 30
        while True:
            piper.ModeCtrl(0x01, 0x01, 50, 0x00)
            piper.JointCtrl(*TARGET_MDEG)
            time.sleep(0.05)
            status = piper.GetArmStatus().arm_status
            assert as_int(status.arm_status) == 0, f"arm_status {as_int(status.arm_status):#04x}"
            err = max(abs(a - b) for a, b in zip(joints_mdeg(piper), TARGET_MDEG))
            if as_int(status.motion_status) == 0 and err <= 100:
                break
            assert time.monotonic() < deadline, f"MOVE J did not arrive: {joints_mdeg(piper)}"
        assert as_int(status.ctrl_mode) == 0x01 and as_int(status.mode_feed) == 0x01

        # Gripper.
        def gripper_there():
            piper.GripperCtrl(GRIPPER_UM, 1000, 0x01, 0)
            stroke = piper.GetArmGripperMsgs().gripper_state.grippers_angle
            return abs(stroke - GRIPPER_UM) <= 1000 and stroke

        wait_for(gripper_there, 15, f"gripper stroke {GRIPPER_UM} um", poll_s=0.05)

        wait_for(lambda: not piper.DisablePiper(), 10, "all joints disabled", poll_s=0.05)
    finally:
        piper.DisconnectPort()
