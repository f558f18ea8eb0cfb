"""Every Python emulator reaches its faults through the emulator's one fault desk: it lists the
emulator's fault table (the one scenario files and the web view use), remembers what was
injected and not cleared, refuses with the builder's messages, and stops the same way."""

import math
from pathlib import Path

import pytest

import armhil.sim

ARM6 = Path(__file__).resolve().parents[2] / "robots" / "robstride_arm6.yaml"


def by_name(emu):
    return {f["name"]: f for f in emu.faults()}


def test_the_piper_lists_its_table_with_defaults_ranges_and_words():
    with armhil.sim.piper() as emu:
        table = by_name(emu)
        assert len(table) == 13
        temp = {p["name"]: p for p in table["motor_over_temp"]["params"]}
        assert temp["joint"]["required"] is True
        assert temp["temp_c"]["required"] is False
        assert temp["temp_c"]["default"] == 90.0
        torque = {p["name"]: p for p in table["external_torque"]["params"]}["torque_nm"]
        assert (torque["min"], torque["max"]) == (-320.0, 320.0)
        board = table["ntc_over_temp"]["params"][0]
        assert board["words"] == ["main", "brake_resistor"]

        emu.inject("stall", joint=2)
        emu.inject("motor_over_temp", joint=3, temp_c=95)
        emu.inject("motor_over_temp", joint=3, temp_c=99)  # the same site: replaced
        assert emu.active_faults == ["stall joint 2", "motor_over_temp joint 3 99 C"]
        emu.clear("stall", joint=2)
        assert emu.active_faults == ["motor_over_temp joint 3 99 C"]
    assert not emu.running
    with pytest.raises(RuntimeError, match="the Piper emulator is stopped"):
        emu.inject("estop")


def test_the_realman_clears_by_name_and_keeps_no_event():
    with armhil.sim.realman() as emu:
        table = by_name(emu)
        delay = table["reply_delay"]["params"][0]
        assert (delay["name"], delay["min"], delay["max"]) == ("delay_ms", 1.0, 60000.0)
        assert [p["name"] for p in table["connection_drop"]["params"]] == ["peer_ip"]
        emu.inject("estop")
        emu.inject("connection_drop")  # an event: nothing to clear
        assert emu.active_faults == ["estop"]
        emu.clear("estop")
        assert emu.active_faults == []
        with pytest.raises(ValueError, match=r"^no Realman fault `comm_loss`; known: "):
            emu.clear("comm_loss")


def test_the_robstride_table_suggests_the_configured_motor():
    with armhil.sim.robstride(motors=["9:RS02", "3:RS03"]) as emu:
        motor = by_name(emu)["gate_driver"]["params"][0]
        assert (motor["name"], motor["default"], motor["min"], motor["max"]) == ("motor", 9.0, 1.0, 127.0)
        emu.inject("gate_driver", motor=3)
        assert emu.active_faults == ["gate_driver on motor 3"]


def test_a_robots_push_and_bus_cut_are_faults_of_its_table():
    with armhil.sim.robot(ARM6) as robot:
        table = by_name(robot)
        assert table["bus_lost"]["params"][0]["default"] == robot.buses[0]
        joint = table["over_temperature"]["params"][0]
        assert joint["name"] == "joint" and joint["default"] in robot.actuators
        robot.set_external_torque("shoulder_yaw", 8.0)
        robot.bus_lost("can1")
        robot.inject("over_temperature", "elbow_pitch")  # `joint` by position
        assert robot.active_faults == [
            "external_torque on shoulder_yaw",
            "bus_lost can1",
            "over_temperature on elbow_pitch",
        ]
        robot.set_external_torque("shoulder_yaw", 0.0)
        robot.bus_lost("can1", lost=False)
        assert robot.active_faults == ["over_temperature on elbow_pitch"]
        # A push beyond ten times the actuator's peak torque never reaches the physics.
        with pytest.raises(ValueError, match=r"^`torque_nm` must be between "):
            robot.set_external_torque("shoulder_yaw", 1e6)
        with pytest.raises(ValueError, match=r"^no actuator drives joint `elbow_pich`; did you mean `elbow_pitch`\?"):
            robot.inject("over_temperature", "elbow_pich")
        with pytest.raises(ValueError, match=r"^the robot has no bus `can9`"):
            robot.bus_lost("can9")


def test_a_robot_takes_every_fault_of_its_table_by_keyword():
    with armhil.sim.robot(ARM6) as robot:
        glitch = {p["name"]: p for p in by_name(robot)["encoder_glitch"]["params"]}
        assert list(glitch) == ["joint", "counts"]
        assert (glitch["counts"]["min"], glitch["counts"]["max"]) == (-8192.0, 8192.0)
        robot.inject("encoder_glitch", joint="shoulder_yaw", counts=2048)
        robot.inject("external_torque", joint="elbow_pitch", torque_nm=3.0)
        robot.inject("bus_lost", bus="can1")
        assert robot.active_faults == [
            "encoder_glitch 2048 counts on shoulder_yaw",
            "external_torque on elbow_pitch",
            "bus_lost can1",
        ]
        # The actuator's encoder reads a quarter turn off the joint's position in the world.
        joint = robot.state()["joints"]["shoulder_yaw"]
        assert joint["angle_rad"] - joint["position_rad"] == pytest.approx(math.pi / 4, abs=0.01)
        robot.clear("encoder_glitch", joint="shoulder_yaw")
        robot.clear("external_torque", joint="elbow_pitch")
        robot.clear("bus_lost", bus="can1")
        assert robot.active_faults == []
        with pytest.raises(ValueError, match=r"^fault `bus_lost` has no argument `joint`; it takes: bus$"):
            robot.inject("bus_lost", "can1")
        with pytest.raises(ValueError, match=r"^fault `encoder_glitch` has no argument `cnts`; it takes: joint, counts$"):
            robot.inject("encoder_glitch", joint="shoulder_yaw", cnts=5)
        with pytest.raises(ValueError, match=r"^`encoder_glitch` needs `counts`$"):
            robot.inject("encoder_glitch", joint="shoulder_yaw")


@pytest.mark.parametrize("start", [
    armhil.sim.realman,
    armhil.sim.piper,
    armhil.sim.robstride,
    lambda: armhil.sim.robot(ARM6),
], ids=["realman", "piper", "robstride", "robot"])
def test_inject_is_documented_with_every_fault_of_the_table(start):
    with start() as emu:
        doc = type(emu).inject.__doc__
        missing = [name for name in by_name(emu) if name not in doc]
        assert missing == [], f"{type(emu).__name__}.inject's docstring does not name {missing}"
        # One signature for every kind: the fault's name, then its table's arguments by
        # keyword; a keyword the table does not have is refused by name.
        for name in by_name(emu):
            with pytest.raises(ValueError, match=r"`no_such_arg`"):
                emu.inject(name, no_such_arg=1)
            if isinstance(emu, armhil.sim.RealmanEmulator):
                continue  # the Realman clears by kind, whatever the arguments
            with pytest.raises(ValueError, match=r"`no_such_arg`"):
                emu.clear(name, no_such_arg=1)
        assert emu.active_faults == []
