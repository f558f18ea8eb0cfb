"""A whole robot under Python control (``armhil.sim.robot`` and the ``robot_emulator`` fixture),
reached by python-can's socketcand interface on two of its buses, as a RobStride client of a
real robot would be (one ``can.Bus`` per bus)."""

import os
import time
from pathlib import Path

import pytest

if os.environ.get("CI"):
    # In CI scripts/ci/python.sh installs it: a missing client is a failure, not a skip.
    import can
else:
    can = pytest.importorskip("can")

import armhil.sim  # noqa: E402

ROBOTS = Path(__file__).resolve().parents[2] / "robots"
ARM6 = ROBOTS / "robstride_arm6.yaml"
HOST_ID = 0xFD
ENABLE, FEEDBACK = 3, 2
MODE_RUN = 2


def open_bus(robot, channel):
    return can.Bus(interface="socketcand", host=robot.host, port=robot.port, channel=channel)


def enable(bus, motor):
    frame_id = (ENABLE << 24) | (HOST_ID << 8) | motor
    bus.send(can.Message(arbitration_id=frame_id, is_extended_id=True, data=bytes(8)))


def feedback_from(bus, motor, timeout_s=1.0):
    """The first feedback frame (type 2) motor `motor` sends within `timeout_s`, or None."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = bus.recv(timeout=0.05)
        if msg is not None and msg.arbitration_id >> 24 == FEEDBACK:
            if (msg.arbitration_id >> 8) & 0xFF == motor:
                return msg
    return None


def test_each_actuator_answers_on_its_own_bus_only(robot_emulator):
    robot = robot_emulator(ARM6)
    assert robot.name == "robstride_arm6"
    assert robot.buses == ["can0", "can1"]
    assert robot.actuators["wrist_roll"] == ("can1", 4)
    with open_bus(robot, "can0") as can0, open_bus(robot, "can1") as can1:
        enable(can1, 4)
        reply = feedback_from(can1, 4)
        assert reply is not None, "motor 4 did not answer on can1"
        assert (reply.arbitration_id >> 22) & 0b11 == MODE_RUN
        assert reply.arbitration_id & 0xFF == HOST_ID
        # Motor 4 is not on can0: nothing answers there.
        enable(can0, 4)
        assert feedback_from(can0, 4, timeout_s=0.3) is None
    joints = robot.state()["joints"]
    assert joints["wrist_roll"]["mode"] == "run"
    assert joints["shoulder_yaw"]["mode"] == "reset"


def test_a_fault_and_a_lost_bus_reach_the_wire(robot_emulator):
    robot = robot_emulator(ARM6)
    with open_bus(robot, "can1") as can1:
        robot.inject("over_temperature", joint="wrist_pitch")
        wrist = robot.state()["joints"]["wrist_pitch"]
        assert wrist["faults"] == ["over_temperature"], wrist
        assert wrist["fault_word"] != 0 and wrist["kind"] == "robstride", wrist
        enable(can1, 5)
        reply = feedback_from(can1, 5)
        assert reply is not None
        fault_bits = (reply.arbitration_id >> 16) & 0x3F
        assert fault_bits != 0, hex(reply.arbitration_id)

        robot.bus_lost("can1")
        assert robot.state()["lost_buses"] == ["can1"]
        enable(can1, 4)
        assert feedback_from(can1, 4, timeout_s=0.3) is None
        robot.bus_lost("can1", lost=False)
        enable(can1, 4)
        assert feedback_from(can1, 4) is not None


def test_a_push_turns_an_unpowered_joint_in_the_physics():
    with armhil.sim.robot(ARM6) as robot:
        start = robot.state()["joints"]["shoulder_yaw"]["position_rad"]
        robot.set_external_torque("shoulder_yaw", 10.0)
        time.sleep(0.5)
        state = robot.state()
        moved = state["joints"]["shoulder_yaw"]["position_rad"] - start
        assert state["time_s"] >= 0.4
        assert moved > 0.05, f"the pushed shoulder turned only {moved} rad in 0.5 s"
        # The actuator's encoder sees the same motion (direction +1, no zero offset).
        assert state["joints"]["shoulder_yaw"]["angle_rad"] == pytest.approx(
            state["joints"]["shoulder_yaw"]["position_rad"], abs=0.01)
    assert not robot.running


def test_a_bad_robot_file_is_named_with_its_line(tmp_path):
    bad = tmp_path / "robot.yaml"
    bad.write_text(ARM6.read_text().replace("urdf: ../urdf/", f"urdf: {ROBOTS.parent}/urdf/")
                   .replace("joint: elbow_pitch", "joint: elbo_pitch"))
    with pytest.raises(ValueError, match=r"robot\.yaml:\d+:\d+: the URDF has no movable joint "
                                         r"`elbo_pitch`; did you mean `elbow_pitch`\?"):
        armhil.sim.robot(bad)
    # The YAML reader's complaints are worded as everywhere else in armhil.
    typo = tmp_path / "typo.yaml"
    typo.write_text(bad.read_text().replace("base: fixed", "bsae: fixed"))
    with pytest.raises(ValueError, match=r"typo\.yaml:\d+:\d+: unknown key `bsae`.*did you mean `base`\?"):
        armhil.sim.robot(typo)
    with pytest.raises(OSError, match="nosuch.yaml"):
        armhil.sim.robot(tmp_path / "nosuch.yaml")


HUMANOID = ROBOTS / "humanoid.yaml"


def test_a_humanoid_hangs_on_its_gantry_until_released():
    # The default for a floating robot: held until every actuator is enabled.
    with armhil.sim.robot(HUMANOID) as robot:
        time.sleep(0.3)
        state = robot.state()
        assert state["gantry_holds"]
        assert state["base_position_m"][2] == pytest.approx(0.81, abs=1e-9)
    with armhil.sim.robot(HUMANOID, gantry="until_released") as robot:
        robot.release_gantry()
        time.sleep(1.5)
        state = robot.state()
        assert not state["gantry_holds"]
        assert state["base_position_m"][2] < 0.6, "unpowered and let go, it falls"
    with armhil.sim.robot(HUMANOID, gantry="off") as robot:
        assert not robot.state()["gantry_holds"]
    with pytest.raises(ValueError, match="gantry must be one of off, until_enabled, until_released"):
        armhil.sim.robot(HUMANOID, gantry="sometimes")
