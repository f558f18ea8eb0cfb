"""LeRobot's OpenArm follower (PyPI `lerobot` 0.6.1, unchanged) against the emulated OpenArm,
`armhil sim robot robots/openarm.yaml --socketcand`, over python-can's socketcand interface.

Run (after `cargo build --bin armhil`), in a Python 3.12 venv (lerobot 0.6.1 needs 3.12 or newer;
`lerobot[openarms]` would pull in torchvision, OpenCV, gymnasium and more that the follower never
imports, so the package goes in without its dependencies, then what its import chain needs):

    pip install --no-compile --no-deps lerobot==0.6.1
    pip install --no-compile torch==2.11.0 numpy==2.2.6 draccus==0.11.6 \\
        huggingface-hub==1.33.0 tqdm==4.70.1 python-can==4.6.1 pytest==8.3.4
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_lerobot_openarm.py

torch is there only because `lerobot.lerobot_types` and `lerobot.utils` import it at module level;
the follower's code path never calls it. PyPI's torch for Linux x86-64 is the CUDA build and does
not import without its nvidia-* wheels: about 3 GB to fetch, 4.7 GB installed, under two minutes
with `--no-compile` (over four without: pip byte-compiles every module of torch).

How LeRobot reaches the emulator. Its Damiao bus (`lerobot/motors/damiao/damiao.py`) opens
`can.interface.Bus(channel=port, bitrate=..., interface=can_interface)`, adding `fd=True` and
`data_bitrate` only when `can_interface == "socketcan"`. The follower's config has the fields
`can_interface` and `use_can_fd`, so the test sets `can_interface="socketcand"` (and, for the single
arm, `use_can_fd=False`): everything else is the config as shipped. It cannot pass a host and port,
so python-can's configuration supplies them (the CAN_CONFIG environment variable), as for
damiao-motor: channel `can0` is the right arm's bus, `can1` the left arm's. The bimanual test
keeps the default `use_can_fd=True`: LeRobot then builds `can.Message(..., is_fd=True)`, which
python-can's socketcand interface writes as a classic `< send ID 8 … >` (it has no FD form; every
LeRobot frame is 8 bytes), so both settings put the same classic frames on the emulated bus.

What LeRobot does that the tests rely on (0.6.1):
- `connect()`: a handshake (an enable `FF…FC` to each motor, waiting 0.1 s for its reply on the
  feedback id), then, with a calibration file present, no interactive calibration; `configure()`
  disables every motor (`FD`) and enables each (`FC`) twice (its `configure_motors()`, then the
  end of its `torque_disabled()`), and `connect()` enables each once more: five special frames
  per motor. The calibration file holds only the ranges LeRobot's own `calibrate()` writes;
  without it LeRobot would prompt on stdin, so `input` is made to fail here;
- `get_observation()`: a refresh (0x7FF `CC`) to each motor, replies collected for 10 ms; joint
  positions in **degrees** (the motors speak radians);
- `send_action({"joint_4.pos": deg, …})`: clips to the side's joint limits, then one MIT frame per
  joint with the config's gains (kp 240 and kd 5 for joint 4), replies collected for 1 ms (those
  that come later are read by the next call, as on the robot);
- `disconnect()`: a disable (`FD`) to each motor, then the bus is shut down.

Disconnect over TCP: python-can's configuration also sets `tcp_tune` (TCP_NODELAY), a socketcand
option of python-can. Without it, LeRobot's `disconnect()` loses some of its disables now and then
(3 disconnects in 60 here): it sends the eight `FD` frames with a 1 ms wait for each reply, then
shuts the bus down at once. Nagle's algorithm holds the last `< send … >` lines in the client's
kernel (unacknowledged data in flight), and closing a socket that still has unread input (the
motors' late replies) makes the kernel reset the connection and drop what it had not sent yet. A
capture of one such run: `< send 001 8 ff ff ff ff ff ff ff fd >` in one segment, 002..004
coalesced in the next, then the client's RST; 005..008 never left the client, and the emulator
put 001..004 on the bus. Real socketcand would see the same; on SocketCAN (LeRobot's default)
each send is a datagram and nothing is lost.

What is checked independently of LeRobot: the emulator's joint angles from its web view's
`/state.json` (`--ui`), and the motors' state nibble from a second python-can client that sends
its own refresh before LeRobot connects and after it disconnects (LeRobot's bus would read the
replies of a refresh sent while it is connected), or reads the motors' replies to LeRobot's frames.

Known difference, not the emulator's: LeRobot's tables give the DM4340 (joints 3, 4) VMAX 8 rad/s,
the older value (docs/protocols/damiao.md §10, §12 #1); the emulated motors use 10. LeRobot's
`joint_3.vel`/`joint_4.vel` are therefore 0.8 of the true speed; positions and torques (PMAX 12.5,
TMAX 28) agree. The velocities are not asserted here.
"""

import json
import os
import sys
import threading
import time
import urllib.request

import pytest

from armhil_process import REPO, free_port, listening

LEROBOT = "lerobot 0.6.1"
if sys.version_info < (3, 12):
    # .ci/run runs this file in a Python 3.12 venv of its own; the suite's interpreter skips it.
    pytest.skip(f"{LEROBOT} needs Python 3.12 or newer (this is {sys.version.split()[0]})",
                allow_module_level=True)
if os.environ.get("CI"):
    # In CI's Python 3.12 venv both are installed by .ci/run: a missing package is a failure.
    import can
    from lerobot.robots.bi_openarm_follower import BiOpenArmFollower, BiOpenArmFollowerConfig
    from lerobot.robots.openarm_follower import OpenArmFollower, OpenArmFollowerConfig
    from lerobot.robots.openarm_follower.config_openarm_follower import OpenArmFollowerConfigBase
else:
    can = pytest.importorskip("can")
    pytest.importorskip("lerobot", reason=f"{LEROBOT} is not installed (see this file's docstring)")
    from lerobot.robots.bi_openarm_follower import BiOpenArmFollower, BiOpenArmFollowerConfig
    from lerobot.robots.openarm_follower import OpenArmFollower, OpenArmFollowerConfig
    from lerobot.robots.openarm_follower.config_openarm_follower import OpenArmFollowerConfigBase

# LeRobot's motor names, in command-id order (1..8), and the emulator's actuators per arm
# (robots/openarm.yaml, the web view's strip order).
MOTORS = ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6", "joint_7", "gripper"]
EMULATED = {
    side: [f"{side}_joint{i}" for i in range(1, 8)] + [f"{side}_gripper"]
    for side in ("right", "left")
}
BUS = {"right": "can0", "left": "can1"}
IDS = range(1, 9)
FEEDBACK_OFFSET = 0x10
PARAM_ID = 0x7FF
PMAX = 12.5  # every OpenArm motor's position range, ± rad
ELBOW = "joint_4"
MOVE_RAD = 0.3
RAMP_S = 0.5
RAD = 180.0 / 3.141592653589793
STATE_DISABLED, STATE_ENABLED = 0, 1


@pytest.fixture()
def openarm(monkeypatch):
    """`armhil sim robot robots/openarm.yaml --socketcand 127.0.0.1:PORT --ui 127.0.0.1:UI`,
    with python-can's configuration pointing at it; yields (port, ui_port)."""
    port, ui_port = free_port(), free_port()
    robot = REPO / "robots" / "openarm.yaml"
    args = ["sim", "robot", str(robot), "--socketcand", f"127.0.0.1:{port}",
            "--ui", f"127.0.0.1:{ui_port}"]
    # LeRobot's `can.interface.Bus(channel, bitrate, interface)` takes host and port from here,
    # and tcp_tune (TCP_NODELAY): see the docstring, "disconnect over TCP".
    monkeypatch.setenv("CAN_CONFIG",
                       json.dumps({"host": "127.0.0.1", "port": port, "tcp_tune": True}))
    with listening(args, port) as proc:
        wait_for(lambda: emulator_state(ui_port, quiet=True), 10, "the web view's /state.json")
        yield port, ui_port
    assert proc.returncode == 0, f"emulator exit {proc.returncode}: {proc.stderr_tail}"


@pytest.fixture()
def calibration_dir(tmp_path, monkeypatch):
    """A folder for LeRobot's calibration files; `input` fails, so that a prompt for an
    interactive calibration is an error rather than a hang."""
    def no_prompt(prompt=""):
        raise AssertionError(f"LeRobot asked for input: {prompt!r}")

    monkeypatch.setattr("builtins.input", no_prompt)
    return tmp_path / "calibration"


def write_calibration(directory, robot_id):
    """The file LeRobot's `OpenArmFollower.calibrate()` writes (ranges ±90°), for ROBOT_ID."""
    directory.mkdir(parents=True, exist_ok=True)
    entries = {name: {"id": i, "drive_mode": 0, "homing_offset": 0, "range_min": -90,
                      "range_max": 90} for i, name in zip(IDS, MOTORS)}
    (directory / f"{robot_id}.json").write_text(json.dumps(entries, indent=4))


def emulator_state(ui_port, quiet=False):
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{ui_port}/state.json", timeout=2) as r:
            return json.load(r)
    except OSError:
        if quiet:
            return None
        raise


def emulator_joints_deg(ui_port, side):
    """The emulator's joint angles of SIDE's arm in degrees, by LeRobot's motor name."""
    with urllib.request.urlopen(f"http://127.0.0.1:{ui_port}/hello.json", timeout=2) as r:
        names = json.load(r)["strip_names"]
    by_name = dict(zip(names, emulator_state(ui_port)["joints_deg"], strict=True))
    return {m: by_name[actuator] for m, actuator in zip(MOTORS, EMULATED[side])}


class Sniffer:
    """A plain python-can client on CHANNEL recording every frame it receives (LeRobot's and the
    motors'), read in a thread so that no backlog builds up."""

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

    def sent_to(self, motor_id, start=0):
        """Frames on the bus to MOTOR_ID (its command id) from index START on."""
        return [bytes(m.data) for m in self.frames[start:] if m.arbitration_id == motor_id]

    def replies(self, start=0):
        """Feedback frames of the motors from index START on, as (id, state, position rad)."""
        return [(m.arbitration_id - FEEDBACK_OFFSET,) + feedback(m) for m in self.frames[start:]
                if m.arbitration_id - FEEDBACK_OFFSET in IDS]

    def refresh(self):
        """Its own refresh (0x7FF CC) to every motor: {id: (state, position rad)} of the replies."""
        start = len(self.frames)
        for i in IDS:
            self.bus.send(can.Message(arbitration_id=PARAM_ID, data=[i, 0, 0xCC, 0, 0, 0, 0, 0],
                                      is_extended_id=False))
        def answered():
            got = {i: (s, p) for i, s, p in self.replies(start)}
            return got if got.keys() == set(IDS) else None

        return wait_for(answered, 2, "a reply to every refresh")

    def close(self):
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join(2)
        self.bus.shutdown()


def feedback(msg):
    """(state nibble, position rad) of a Damiao feedback frame (docs/protocols/damiao.md §5)."""
    d = bytes(msg.data)
    return d[0] >> 4, ((d[1] << 8) | d[2]) * 2 * PMAX / 0xFFFF - PMAX


def mit_command(data):
    """(p_des rad, kp, kd) of an MIT command frame (docs/protocols/damiao.md §3.1)."""
    p = ((data[0] << 8) | data[1]) * 2 * PMAX / 0xFFFF - PMAX
    kp = (((data[3] & 0xF) << 8) | data[4]) * 500 / 0xFFF
    kd = ((data[5] << 4) | (data[6] >> 4)) * 5 / 0xFFF
    return p, kp, kd


def wait_for(predicate, timeout_s, what, poll_s=0.01):
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(poll_s)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what} (last: {last!r})")


def positions(obs, prefix=""):
    return {m: float(obs[f"{prefix}{m}.pos"]) for m in MOTORS}


def assert_matches_emulator(obs_deg, ui_port, side, tol_rad):
    emulated = emulator_joints_deg(ui_port, side)
    for m in MOTORS:
        assert abs(obs_deg[m] - emulated[m]) < tol_rad * RAD, (
            f"{side} {m}: LeRobot {obs_deg[m]:.3f}° vs emulator {emulated[m]:.3f}°")


def run_loop(robot, action_at, seconds, period_s=0.01):
    """LeRobot's control loop: send_action(ACTION_AT(t)) then get_observation every PERIOD_S for
    SECONDS; returns the observations and the last action LeRobot reports it sent."""
    observations, sent = [], None
    start = time.monotonic()
    while (t := time.monotonic() - start) < seconds:
        sent = robot.send_action(action_at(t))
        observations.append(robot.get_observation())
        time.sleep(period_s)
    return observations, sent


def ramp(hold, key, delta_deg):
    """Actions holding HOLD (action key -> degrees) with KEY going to HOLD[KEY] + DELTA_DEG over
    RAMP_S, as a leader arm would stream them: a step of 0.3 rad at kp 240 throws the joints
    around it by 3 degrees, the arm's physics, not the follower's."""
    def action_at(t):
        return {**hold, key: hold[key] + delta_deg * min(1.0, t / RAMP_S)}

    return action_at


def test_right_arm_follower_connects_reads_moves_the_elbow_and_disconnects(openarm,
                                                                           calibration_dir):
    port, ui_port = openarm
    right, left = Sniffer(port, BUS["right"]), Sniffer(port, BUS["left"])
    robot = None
    try:
        # Power-on: every motor disabled, at the emulator's pose (the arm hangs near zero).
        before = right.refresh()
        assert {i: s for i, (s, _) in before.items()} == dict.fromkeys(IDS, STATE_DISABLED)
        emulated = emulator_joints_deg(ui_port, "right")
        for i, m in zip(IDS, MOTORS):
            assert abs(before[i][1] * RAD - emulated[m]) < 0.02 * RAD, (m, before[i], emulated[m])
            assert abs(emulated[m]) < 10, f"{m} not near the rest pose: {emulated[m]}°"

        robot_id = "armhil_right"
        write_calibration(calibration_dir, robot_id)
        config = OpenArmFollowerConfig(
            id=robot_id, calibration_dir=calibration_dir, port=BUS["right"], side="right",
            can_interface="socketcand", use_can_fd=False, use_velocity_and_torque=True)
        robot = OpenArmFollower(config)
        assert robot.is_calibrated, "the calibration file was not picked up"
        mark = len(right.frames)
        t0 = time.monotonic()
        robot.connect()
        connect_s = time.monotonic() - t0
        assert robot.is_connected
        assert connect_s < 5, f"connect took {connect_s:.2f} s"
        # Handshake, configure and enable: FC, FD, FC, FC, FC to every motor, and nothing else;
        # every motor's last reply says enabled.
        expected = [b"\xff" * 7 + bytes([c]) for c in (0xFC, 0xFD, 0xFC, 0xFC, 0xFC)]
        wait_for(lambda: all(len(right.sent_to(i, mark)) >= len(expected) for i in IDS), 2,
                 "LeRobot's enables and disables as the sniffer sees them")
        for i in IDS:
            sent = right.sent_to(i, mark)
            assert sent == expected, (i, [d.hex() for d in sent])
        wait_for(lambda: {i: s for i, s, _ in right.replies(mark)} == dict.fromkeys(
            IDS, STATE_ENABLED), 2, "every motor's last reply to say enabled")

        obs = robot.get_observation()
        assert set(obs) == {f"{m}.{k}" for m in MOTORS for k in ("pos", "vel", "torque")}
        hold = positions(obs)
        # Enabled with no command yet, the motors give no torque and the arm sags a little:
        # LeRobot's reading (its replies may be a cycle old) and the emulator's are not of one
        # instant, hence 0.05 rad here and 0.02 rad once the arm is held still.
        assert_matches_emulator(hold, ui_port, "right", 0.05)

        # The elbow up by MOVE_RAD, every other joint held where it was.
        key = f"{ELBOW}.pos"
        action_at = ramp({f"{m}.pos": v for m, v in hold.items()}, key, MOVE_RAD * RAD)
        target = action_at(RAMP_S)
        mark = len(right.frames)
        observations, sent = run_loop(robot, action_at, RAMP_S + 1.0)
        assert sent[key] == pytest.approx(target[key]), "clipped"
        final = positions(observations[-1])
        assert abs(final[ELBOW] - target[key]) < 0.02 * RAD, (
            f"elbow at {final[ELBOW]:.2f}°, target {target[key]:.2f}°: "
            f"{[round(positions(o)[ELBOW], 2) for o in observations[::10]]}")
        assert_matches_emulator(final, ui_port, "right", 0.02)
        # The torque LeRobot decodes is the motor's MIT law at the position of the same frame,
        # kp·(p_des − p) − kd·v with the config's gains (the elbow's holds the forearm against
        # gravity): LeRobot's TMAX and PMAX scaling agree with the motors'.
        last = observations[-1]
        for k, m in enumerate(MOTORS):
            law = (config.position_kp[k] * (sent[f"{m}.pos"] - last[f"{m}.pos"])
                   - config.position_kd[k] * last[f"{m}.vel"]) / RAD
            assert abs(last[f"{m}.torque"] - law) < 0.5, (m, last[f"{m}.torque"], law)
        assert abs(last[f"{ELBOW}.torque"]) > 0.5, "the held forearm weighs nothing"
        for m in MOTORS:
            if m != ELBOW:
                worst = max(abs(positions(o)[m] - hold[m]) for o in observations)
                assert worst < 0.05 * RAD, f"{m} moved {worst:.2f}° while held"
        # On the wire: LeRobot's MIT frames to the elbow carry the target in radians and the
        # config's gains (kp 240, kd 5 for joint 4), and the motors answered enabled.
        p_des, kp, kd = mit_command(right.sent_to(4, mark)[-1])
        assert p_des == pytest.approx(target[key] / RAD, abs=1e-3)
        assert (kp, kd) == (pytest.approx(240, abs=0.2), pytest.approx(5, abs=0.01))
        assert {s for _, s, _ in right.replies(mark)} == {STATE_ENABLED}
        # Every frame anyone put on can0 was a classic 8-byte frame with a standard id.
        assert {(m.dlc, m.is_extended_id) for m in right.frames} == {(8, False)}

        mark = len(right.frames)
        robot.disconnect()
        assert not robot.is_connected
        wait_for(lambda: {i: s for i, s, _ in right.replies(mark)} == dict.fromkeys(
            IDS, STATE_DISABLED), 2, "every motor's reply to LeRobot's disable")
        for i in IDS:
            assert right.sent_to(i, mark) == [b"\xff" * 7 + b"\xfd"], i
        after = right.refresh()
        assert {i: s for i, (s, _) in after.items()} == dict.fromkeys(IDS, STATE_DISABLED)
        # The left arm's bus carried nothing: LeRobot spoke on can0 only, and the motors send
        # nothing unasked.
        assert left.frames == [], left.frames[:5]
    finally:
        if robot is not None and robot.is_connected:
            robot.disconnect()
        right.close()
        left.close()


def test_bimanual_follower_moves_the_left_elbow_only(openarm, calibration_dir):
    port, ui_port = openarm
    sniffers = {side: Sniffer(port, bus) for side, bus in BUS.items()}
    robot = None
    try:
        robot_id = "armhil_bi"
        for side in ("left", "right"):
            write_calibration(calibration_dir, f"{robot_id}_{side}")
        # Each arm as shipped but for can_interface (use_can_fd stays True: see the docstring).
        config = BiOpenArmFollowerConfig(
            id=robot_id, calibration_dir=calibration_dir,
            left_arm_config=OpenArmFollowerConfigBase(
                port=BUS["left"], side="left", can_interface="socketcand"),
            right_arm_config=OpenArmFollowerConfigBase(
                port=BUS["right"], side="right", can_interface="socketcand"))
        assert config.left_arm_config.use_can_fd and config.right_arm_config.use_can_fd
        robot = BiOpenArmFollower(config)
        robot.connect()
        assert robot.is_connected
        for side, sniffer in sniffers.items():
            wait_for(lambda: {i: s for i, s, _ in sniffer.replies()} == dict.fromkeys(
                IDS, STATE_ENABLED), 2, f"every {side} motor's last reply to say enabled")

        obs = robot.get_observation()
        assert set(obs) == {f"{side}_{m}.pos" for side in ("left", "right") for m in MOTORS}
        hold = {side: positions(obs, f"{side}_") for side in ("left", "right")}
        for side in ("left", "right"):
            assert_matches_emulator(hold[side], ui_port, side, 0.05)

        action_at = ramp({f"{side}_{m}.pos": v for side in hold for m, v in hold[side].items()},
                         f"left_{ELBOW}.pos", MOVE_RAD * RAD)
        target = action_at(RAMP_S)
        observations, _ = run_loop(robot, action_at, RAMP_S + 1.0)
        final = {side: positions(observations[-1], f"{side}_") for side in ("left", "right")}
        key = f"left_{ELBOW}.pos"
        assert abs(final["left"][ELBOW] - target[key]) < 0.02 * RAD, (
            f"left elbow at {final['left'][ELBOW]:.2f}°, target {target[key]:.2f}°")
        for side in ("left", "right"):
            assert_matches_emulator(final[side], ui_port, side, 0.02)
            for m in MOTORS:
                if (side, m) != ("left", ELBOW):
                    worst = max(abs(positions(o, f"{side}_")[m] - hold[side][m])
                                for o in observations)
                    assert worst < 0.05 * RAD, f"{side} {m} moved {worst:.2f}° while held"
        # use_can_fd=True made no difference on the wire: classic 8-byte frames only.
        for sniffer in sniffers.values():
            assert {(m.dlc, m.is_extended_id) for m in sniffer.frames} == {(8, False)}

        robot.disconnect()
        assert not robot.is_connected
        for side, sniffer in sniffers.items():
            after = sniffer.refresh()
            assert {i: s for i, (s, _) in after.items()} == dict.fromkeys(IDS, STATE_DISABLED), side
    finally:
        if robot is not None and robot.is_connected:
            robot.disconnect()
        for sniffer in sniffers.values():
            sniffer.close()
