"""The Damiao client damiao-motor 1.0.6 (PyPI, unchanged) against the emulated OpenArm,
`armhil sim robot robots/openarm.yaml --socketcand`, over python-can's socketcand interface.

Run (after `cargo build --bin armhil`):

    pip install python-can==4.6.1 damiao-motor==1.0.6 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_damiao_motor.py

The client opens its bus as `can.interface.Bus(channel=..., bustype=...)` and cannot pass a host
and port, so python-can's configuration supplies them (the CAN_CONFIG environment variable), as
for piper_sdk: `DaMiaoController(channel="can0", bustype="socketcand")` then reaches the
emulator's bus can0 (the right arm) and `channel="can1"` the left arm.

Three tests: the right arm through the client's API (registers, enable, hold, the elbow to
0.8 rad, the left arm untouched, disable); a register write and the CAN timeout with the
client's own recovery; the package's command line (`damiao scan`).

What the client does that the tests rely on or watch for (damiao_motor/core/):
- one background thread per controller reads the bus (`recv(timeout=0)` every ms) and routes a
  frame on the low nibble of D0 alone, whatever its identifier;
- a frame with D1 <= 0x0F, D2 = 0x33 and a known RID is a register reply; **any other 8-byte
  frame is feedback**, so the 0x55 echo of a register write is decoded as feedback (state 0,
  position near -PMAX): see `test_register_write_echo_and_can_timeout`;
- `get_register` returns a cached value once it has one and only asks the motor the first time;
- `send_cmd_mit` first sends enable (FC) when the last feedback said state 0 (disabled) and
  clear (FB) when it said state D (communication lost).

The motors send nothing unasked (protocol note §5): feedback is read here after a command or
after the client's refresh (`request_motor_feedback`, 0x7FF `CC`).
"""

import os
import re
import subprocess
import sys
import threading
import time

import pytest

from armhil_process import REPO, free_port, listening

if os.environ.get("CI"):
    # In CI both are installed by .ci/run: a missing package is a failure, not a skip.
    import can
    import damiao_motor
else:
    can = pytest.importorskip("can")
    damiao_motor = pytest.importorskip(
        "damiao_motor", reason="damiao-motor is not installed (pip install damiao-motor==1.0.6)"
    )

# damiao-motor passes `bustype=`, which python-can 4.2+ deprecates (removal in 5.0).
pytestmark = pytest.mark.filterwarnings("ignore:The 'bustype' argument is deprecated")

# The OpenArm's joints by command id, with the client's name of their model (robots/openarm.yaml).
RIGHT_ARM = {1: "8009", 2: "8009", 3: "4340", 4: "4340", 5: "4310", 6: "4310", 7: "4310"}
LEFT_ARM = {**RIGHT_ARM, 8: "4310"}  # with the gripper
FEEDBACK_OFFSET = 0x10  # feedback (MST_ID) = command id + 0x10
ELBOW = 4
ELBOW_TARGET = 0.8  # rad
KP, KD = 60.0, 2.0  # MIT gains like the OpenArm vendor's for these joints
PERIOD_S = 0.005  # 200 Hz command loop

RID_TIMEOUT, RID_CTRL_MODE, RID_MST_ID, RID_ESC_ID = 9, 10, 7, 8
RID_PMAX, RID_VMAX, RID_TMAX = 21, 22, 23


@pytest.fixture()
def openarm(monkeypatch):
    """`armhil sim robot robots/openarm.yaml --socketcand 127.0.0.1:PORT`, with python-can's
    configuration pointing at it; yields the port."""
    port = free_port()
    robot = REPO / "robots" / "openarm.yaml"
    args = ["sim", "robot", str(robot), "--socketcand", f"127.0.0.1:{port}"]
    # damiao-motor's `can.interface.Bus(channel, bustype)` takes host and port from here.
    monkeypatch.setenv("CAN_CONFIG", f'{{"host": "127.0.0.1", "port": {port}}}')
    with listening(args, port) as proc:
        yield port
    assert proc.returncode == 0, f"emulator exit {proc.returncode}: {proc.stderr_tail}"


class Controller:
    """A `DaMiaoController` on CHANNEL with the motors of ARM; `close()` is its `shutdown()`
    (stop polling, disable every motor, close the bus)."""

    def __init__(self, channel, arm):
        self.ctl = damiao_motor.DaMiaoController(channel=channel, bustype="socketcand")
        self.motors = {
            i: self.ctl.add_motor(i, FEEDBACK_OFFSET + i, model) for i, model in arm.items()
        }

    def states(self):
        return {i: m.get_states() for i, m in self.motors.items()}

    def close(self):
        self.ctl.shutdown()


class Sniffer:
    """A plain python-can client on CHANNEL recording every frame it receives, read in a thread
    so that no backlog builds up."""

    def __init__(self, port, channel):
        self.bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel=channel)
        self.frames = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        while not self._stop.is_set():
            msg = self.bus.recv(0.02)
            if msg is not None:
                self.frames.append(msg)

    def close(self):
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join(2)
        self.bus.shutdown()


def wait_for(predicate, timeout_s, what, poll_s=0.01):
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(poll_s)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what} (last: {last!r})")


def statuses(ctl):
    return {i: s.get("status") for i, s in ctl.states().items()}


def drive(ctl, targets, seconds):
    """Sends the client's MIT command (KP, KD) to every motor of TARGETS (id -> rad) every
    PERIOD_S for SECONDS; returns [(t, {id: feedback state})] after each round."""
    samples = []
    start = time.monotonic()
    while (t := time.monotonic() - start) < seconds:
        for i, target in targets.items():
            ctl.motors[i].send_cmd_mit(target_position=target, stiffness=KP, damping=KD)
        samples.append((t, ctl.states()))
        time.sleep(PERIOD_S)
    return samples


def hex_frame(msg):
    return f"{msg.arbitration_id:03X}#{bytes(msg.data).hex().upper()}"


def test_enable_read_registers_hold_and_move_the_elbow(openarm):
    left_sniffer = Sniffer(openarm, "can1")
    right = Controller("can0", RIGHT_ARM)
    try:
        # Registers through the client's own read (0x7FF, op 0x33; reply on MST_ID).
        for i, model in RIGHT_ARM.items():
            motor = right.motors[i]
            preset = damiao_motor.MOTOR_TYPE_PRESETS[model]
            got = {rid: motor.get_register(rid, timeout=2.0) for rid in
                   (RID_CTRL_MODE, RID_MST_ID, RID_ESC_ID, RID_PMAX, RID_VMAX, RID_TMAX)}
            assert got[RID_CTRL_MODE] == 1, f"J{i} CTRL_MODE (1 = MIT)"
            assert (got[RID_ESC_ID], got[RID_MST_ID]) == (i, FEEDBACK_OFFSET + i), f"J{i} ids"
            # The client scales MIT frames with its preset; the motor's ranges must agree.
            assert got[RID_PMAX] == pytest.approx(preset["p_max"]), f"J{i} PMAX"
            assert got[RID_VMAX] == pytest.approx(preset["v_max"]), f"J{i} VMAX"
            assert got[RID_TMAX] == pytest.approx(preset["t_max"]), f"J{i} TMAX"
        # J3 is a DM4340: VMAX 10 rad/s in current tables (8 in older ones, protocol note §12).
        assert right.motors[3].get_register(RID_VMAX) == 10.0

        # Disabled at power-on: the refresh (0x7FF CC) answers with feedback, state 0.
        for motor in right.motors.values():
            motor.request_motor_feedback()
        wait_for(lambda: all(right.states().values()), 2, "a reply to every refresh")
        assert set(statuses(right).values()) == {"DISABLED"}, statuses(right)

        right.ctl.enable_all()
        wait_for(lambda: set(statuses(right).values()) == {"ENABLED"}, 2, "every joint enabled")

        # Hold every joint where it is.
        hold = {i: s["pos"] for i, s in right.states().items()}
        samples = drive(right, hold, 0.5)
        for i in RIGHT_ARM:
            worst = max(abs(states[i]["pos"] - hold[i]) for _, states in samples)
            assert worst < 0.1, f"J{i} drifted {worst:.3f} rad from {hold[i]:.3f} while held"
        assert set(statuses(right).values()) == {"ENABLED"}, statuses(right)

        # Move the elbow to ELBOW_TARGET, the others still held.
        start_pos = right.states()[ELBOW]["pos"]
        assert abs(ELBOW_TARGET - start_pos) > 0.5, f"elbow already at {start_pos:.3f}"
        samples = drive(right, {**hold, ELBOW: ELBOW_TARGET}, 2.0)
        # The elbow gets there in about 0.25 s (at DM4340 speed: the torque falls along its
        # torque-speed line), overshoots a little, sags under gravity and settles.
        error = [(t, ELBOW_TARGET - states[ELBOW]["pos"]) for t, states in samples]
        later = [abs(e) for t, e in error if t >= 0.5]
        assert later and max(later) < 0.15, (
            f"elbow not within 0.15 rad of {ELBOW_TARGET} from 0.5 s on: "
            f"{[round(e, 3) for t, e in error[::10]]}")
        assert min(e for _, e in error) > -0.1, "overshoot beyond 0.1 rad"
        final = right.states()[ELBOW]
        assert final["status"] == "ENABLED"
        assert final["pos"] == pytest.approx(ELBOW_TARGET, abs=0.1), final
        assert abs(final["vel"]) < 0.2, final
        # Settled: the torque reported is what the MIT law applies, kp·(p_des − p) − kd·v
        # (the steady error is gravity on the forearm).
        assert final["torq"] == pytest.approx(
            KP * (ELBOW_TARGET - final["pos"]) - KD * final["vel"], abs=0.5), final
        for i in RIGHT_ARM:
            if i != ELBOW:
                worst = max(abs(states[i]["pos"] - hold[i]) for _, states in samples)
                assert worst < 0.15, f"J{i} moved {worst:.3f} rad while the elbow moved"

        # The left arm's bus carried nothing: the right arm's client spoke on can0 only, and
        # the motors send nothing unasked.
        left_sniffer.close()
        assert left_sniffer.frames == [], [hex_frame(m) for m in left_sniffer.frames[:10]]

        # A second client, on can1, while the right arm holds its elbow up: the left arm is
        # disabled and not where the right elbow went.
        left = Controller("can1", LEFT_ARM)
        try:
            for motor in left.motors.values():
                motor.request_motor_feedback()
            wait_for(lambda: all(left.states().values()), 2, "a reply to every refresh on can1")
            assert set(statuses(left).values()) == {"DISABLED"}, statuses(left)
            for i, state in left.states().items():
                assert state["arbitration_id"] == FEEDBACK_OFFSET + i, state
            assert abs(left.states()[ELBOW]["pos"] - ELBOW_TARGET) > 0.5, left.states()[ELBOW]
        finally:
            left.close()
        right.motors[ELBOW].request_motor_feedback()
        time.sleep(0.1)
        assert right.states()[ELBOW]["status"] == "ENABLED"
        assert right.states()[ELBOW]["pos"] == pytest.approx(ELBOW_TARGET, abs=0.1)

        right.ctl.disable_all()
        wait_for(lambda: set(statuses(right).values()) == {"DISABLED"}, 2, "every joint disabled")
    finally:
        right.close()
        left_sniffer.close()


def test_register_write_echo_and_can_timeout(openarm):
    """The client's register write, as it reads the echo, and the CAN timeout with the client's
    own recovery (FB on state D, then FC on state 0)."""
    sniffer = Sniffer(openarm, "can0")
    right = Controller("can0", {ELBOW: RIGHT_ARM[ELBOW]})
    elbow = right.motors[ELBOW]
    try:
        elbow.enable()
        wait_for(lambda: elbow.get_states().get("status") == "ENABLED", 2, "elbow enabled")

        # set_can_timeout(100 ms) writes TIMEOUT = 2000 (50 µs units): 0x7FF, op 0x55.
        elbow.set_can_timeout(100)
        echo = wait_for(
            lambda: next((m for m in sniffer.frames if m.arbitration_id == FEEDBACK_OFFSET + ELBOW
                          and bytes(m.data[:4]) == bytes([ELBOW, 0, 0x55, RID_TIMEOUT])), None),
            2, "the write's echo on MST_ID",
        )
        assert bytes(echo.data) == bytes([ELBOW, 0, 0x55, RID_TIMEOUT, 0xD0, 0x07, 0, 0])
        # damiao-motor 1.0.6 reads only 0x33 frames as register replies: it decodes this echo
        # as feedback (state 0 from D0 = 0x04, position from D1..D2 = 0x0055, near -PMAX).
        state = wait_for(lambda: elbow.get_states().get("status") == "DISABLED"
                         and elbow.get_states(), 2, "the echo decoded as feedback")
        assert state["pos"] < -12.4, state
        # Stored all the same: a read (not cached yet) returns it.
        assert elbow.get_register(RID_TIMEOUT, timeout=2.0) == 2000

        # Commands keep the watchdog fed. The first one, after the "disabled" echo, is preceded
        # by the client's unasked enable (FC).
        sent_before = len(sniffer.frames)
        drive(right, {ELBOW: 0.0}, 0.3)
        assert elbow.get_states()["status"] == "ENABLED"
        assert any(m.arbitration_id == ELBOW and bytes(m.data) == b"\xff" * 7 + b"\xfc"
                   for m in sniffer.frames[sent_before:])

        # 0.4 s of silence: the motor stops and latches state D (communication lost).
        time.sleep(0.4)
        elbow.request_motor_feedback()
        wait_for(lambda: elbow.get_states().get("status") == "LOST_COMM", 2,
                 "state D after 100 ms without a frame")

        # The client's loop recovers on its own: FB (clear) on seeing D, FC (enable) on seeing
        # 0, then the elbow follows the target again.
        sent_before = len(sniffer.frames)
        samples = drive(right, {ELBOW: ELBOW_TARGET}, 2.0)
        sent = [bytes(m.data) for m in sniffer.frames[sent_before:] if m.arbitration_id == ELBOW]
        clear, enable = b"\xff" * 7 + b"\xfb", b"\xff" * 7 + b"\xfc"
        assert clear in sent and enable in sent and sent.index(clear) < sent.index(enable), [
            s.hex() for s in sent[:6]]
        recovered = [t for t, states in samples if states[ELBOW]["status"] == "ENABLED"]
        assert recovered and recovered[0] < 0.5, "enabled again within a few commands"
        assert elbow.get_states()["pos"] == pytest.approx(ELBOW_TARGET, abs=0.1)

        # TIMEOUT back to 0 (off): the echo says 0.
        elbow.set_can_timeout(0)
        wait_for(lambda: any(m.arbitration_id == FEEDBACK_OFFSET + ELBOW
                             and bytes(m.data) == bytes([ELBOW, 0, 0x55, RID_TIMEOUT, 0, 0, 0, 0])
                             for m in sniffer.frames), 2, "the echo of TIMEOUT = 0")
    finally:
        right.close()
        sniffer.close()


def test_the_damiao_cli_scans_the_right_arm(openarm):
    """The package's own command line, `damiao scan --bustype socketcand` (python-can's
    configuration from CAN_CONFIG as above): a zero MIT command to ids 1..16, then every register
    of its table (RIDs 0..81) read from each motor that answered."""
    scan = subprocess.run(
        [sys.executable, "-c", "from damiao_motor.cli import unified_main; unified_main()",
         "scan", "--channel", "can0", "--bustype", "socketcand"],
        capture_output=True, text=True, timeout=120,
    )
    out = re.sub(r"\x1b\[[0-9;]*m", "", scan.stdout)
    assert scan.returncode == 0, out[-2000:] + scan.stderr[-2000:]
    found = re.findall(r"Motor ID 0x(\w+) responded \(arb_id: 0x(\w+), state: (\w+)", out)
    assert [(int(i, 16), int(a, 16), s) for i, a, s in found] == [
        (i, FEEDBACK_OFFSET + i, "DISABLED") for i in range(1, 9)
    ], out[:3000]
    assert "Found 8 motor(s)" in out
    # Every register of every motor answered (a timeout prints "ERROR: ...").
    assert "ERROR" not in out, [line for line in out.splitlines() if "ERROR" in line][:10]
    vmax = re.findall(r"22\s+VMAX\s+Speed mapping range\s+([\d.]+)", out)
    assert [float(v) for v in vmax] == [45.0, 45.0, 10.0, 10.0, 30.0, 30.0, 30.0, 30.0], vmax
