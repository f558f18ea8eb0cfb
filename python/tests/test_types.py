"""The data classes carry the API's attribute names, are read-write, and check shapes."""

import pytest

import armhil.sim
from armhil import (ArmForceSensor, ArmRealtimeState, GripperState, JointState,
                    PeripheralReadWriteParams, Pose)


def test_attribute_names_are_the_apis():
    js = JointState()
    for name in ["joint_position", "joint_speed", "joint_current", "joint_temperature",
                 "joint_voltage", "joint_err_code", "joint_en_flag"]:
        assert getattr(js, name) == []
    g = GripperState()
    for name in ["status", "error", "mode", "current_force", "temperature", "actpos"]:
        assert getattr(g, name) == 0
    f = ArmForceSensor()
    assert (f.force, f.zero_force, f.coordinate) == ([], [], 0)
    p = PeripheralReadWriteParams(port=1, address=10, device=2, num=3)
    assert (p.port, p.address, p.device, p.num) == (1, 10, 2, 3)
    assert {"name", "timestamp", "joint_status", "force_sensor", "arm_current_status",
            "gripper_state", "ee_pose"} <= set(dir(ArmRealtimeState))


def test_attributes_are_writable():
    js = JointState()
    js.joint_position = [1.0, 2.0]
    assert js.joint_position == [1.0, 2.0]
    g = GripperState()
    g.actpos = 500
    assert g.actpos == 500


def test_pose_checks_its_vectors():
    p = Pose(position=[0.1, 0.2, 0.3], euler=[0.0, 0.1, 0.2])
    assert p.position == [0.1, 0.2, 0.3] and p.euler == [0.0, 0.1, 0.2]
    assert Pose().position == [0.0, 0.0, 0.0]
    p.position = [1.0, 2.0, 3.0]
    assert p.position[2] == 3.0
    with pytest.raises(ValueError):
        Pose(position=[1.0, 2.0])
    with pytest.raises(ValueError):
        p.euler = [0.0]


def test_emulator_options_are_checked():
    with pytest.raises(ValueError):
        armhil.sim.piper(firmware="S-V9.9-9")
    with pytest.raises(ValueError):
        armhil.sim.realman(model="RM99")
    with pytest.raises(ValueError):
        armhil.sim.piper(initial_joints_deg=[0.0, 1.0])
    with armhil.sim.piper(firmware="S-V1.6-3") as emu:
        assert emu.running
