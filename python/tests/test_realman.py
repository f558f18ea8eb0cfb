"""The seed Arm API against the Realman emulator (TCP commands, UDP realtime push)."""

import math
import time

import pytest

from armhil import AbcErrorCode, ArmFactory, ArmRealtimeState, GripperState, Pose

from conftest import TARGET_DEG, measure_rate, returns_within, stops_growing, wait_until


def test_blocking_joint_move_reaches_the_target(realman_arm, realman_emulator):
    assert realman_arm.name == "left_arm"
    code = realman_arm.move_joint_position(TARGET_DEG, 50, 0, 0, 1)
    assert code == AbcErrorCode.SUCCESS, realman_arm.last_error
    code, joints = realman_arm.get_joint_degree()
    assert code == AbcErrorCode.SUCCESS
    assert len(joints) == 6
    for got, want, truth in zip(joints, TARGET_DEG, realman_emulator.joints_deg()):
        assert abs(got - want) < 0.05
        assert abs(truth - want) < 0.05


def test_non_blocking_move_returns_before_arrival(realman_arm, realman_emulator):
    start = time.monotonic()
    code = realman_arm.move_joint_position([0, 40, 60, 0, 50, 0], 20, 0, 0, 0)
    assert code == AbcErrorCode.SUCCESS
    assert time.monotonic() - start < 0.5
    assert wait_until(lambda: realman_emulator.state()["queued_moves"] == 0, 20)
    assert abs(realman_emulator.joints_deg()[1] - 40) < 0.1


def test_forward_and_inverse_kinematics_agree(realman_arm):
    code, pose = realman_arm.forward_kinematics(TARGET_DEG)
    assert code == AbcErrorCode.SUCCESS
    assert isinstance(pose, Pose)
    assert 0.1 < math.dist(pose.position, [0, 0, 0]) < 1.0
    code, joints = realman_arm.inverse_kinematics(pose, TARGET_DEG, 0)
    assert code == AbcErrorCode.SUCCESS, realman_arm.last_error
    assert max(abs(a - b) for a, b in zip(joints, TARGET_DEG)) < 0.1


def test_cartesian_moves_land_on_the_pose(realman_arm, realman_emulator):
    # Tool pointing down in front of the base, then 3 cm lower in a straight line.
    _, pose = realman_arm.forward_kinematics([0, 20, 70, 0, 90, 0])
    assert realman_arm.move_joint_pose(pose, 50, 0, 0, 1) == AbcErrorCode.SUCCESS
    lifted = Pose(position=[pose.position[0], pose.position[1], pose.position[2] - 0.03],
                  euler=pose.euler)
    code = realman_arm.move_cartesian_linear(lifted, 30, 0, 0, 1)
    assert code == AbcErrorCode.SUCCESS, realman_arm.last_error
    z = realman_emulator.state()["position_m"][2]
    assert abs(z - lifted.position[2]) < 0.002


def test_unreachable_pose_is_out_of_range(realman_arm):
    far = Pose(position=[2.0, 0.0, 0.0], euler=[math.pi, 0.0, 0.0])
    code, joints = realman_arm.inverse_kinematics(far, [0.0] * 6, 0)
    assert code == AbcErrorCode.ARM_OUT_OF_RANGE
    assert joints == []
    assert realman_arm.move_joint_pose(far, 50, 0, 0, 1) == AbcErrorCode.ARM_OUT_OF_RANGE
    assert realman_arm.move_cartesian_linear(far, 50, 0, 0, 1) == AbcErrorCode.ARM_OUT_OF_RANGE


def test_out_of_range_arguments_are_codes_not_exceptions(realman_arm):
    assert realman_arm.move_joint_position(TARGET_DEG, 0, 0, 0, 1) == AbcErrorCode.PARAM_OUT_OF_RANGE
    assert realman_arm.move_joint_position(TARGET_DEG, 500, 0, 0, 1) == AbcErrorCode.PARAM_OUT_OF_RANGE
    assert realman_arm.move_joint_position(TARGET_DEG, 50, 0, 0, 7) == AbcErrorCode.PARAM_OUT_OF_RANGE
    assert "block" in realman_arm.last_error
    assert realman_arm.move_joint_position([0.0] * 5, 50, 0, 0, 1) == AbcErrorCode.INVALID_ARGUMENT
    assert realman_arm.set_gripper_position(5000, True, 3) == AbcErrorCode.PARAM_OUT_OF_RANGE
    assert realman_arm.set_hand_angle([1, 2, 3]) == AbcErrorCode.INVALID_ARGUMENT


def test_gripper_release_pick_and_state(realman_arm):
    assert realman_arm.set_gripper_release(500, True, 5) == AbcErrorCode.SUCCESS
    code, g = realman_arm.get_gripper_state()
    assert code == AbcErrorCode.SUCCESS and isinstance(g, GripperState)
    assert g.status == 1 and g.actpos > 900
    assert realman_arm.set_gripper_position(300, True, 5) == AbcErrorCode.SUCCESS
    code, g = realman_arm.get_gripper_state()
    assert abs(g.actpos - 300) < 30
    assert realman_arm.set_gripper_pick(500, 200, True, 5) == AbcErrorCode.SUCCESS


def test_pause_continue_and_stops(realman_arm, realman_emulator):
    assert realman_arm.move_joint_position([0, 60, 60, 0, 60, 0], 10, 0, 0, 0) == AbcErrorCode.SUCCESS
    time.sleep(0.3)
    assert realman_arm.set_arm_pause() == AbcErrorCode.SUCCESS
    time.sleep(0.5)  # the controller decelerates to a stop on the path
    paused = realman_emulator.joints_deg()
    time.sleep(0.3)
    assert max(abs(a - b) for a, b in zip(paused, realman_emulator.joints_deg())) < 0.05
    assert realman_arm.set_arm_continue() == AbcErrorCode.SUCCESS
    assert realman_arm.set_arm_slow_stop() == AbcErrorCode.SUCCESS
    assert realman_arm.set_arm_stop() == AbcErrorCode.SUCCESS


def test_error_flag_and_modbus(realman_arm, realman_emulator):
    code, (errors, brakes) = realman_arm.get_error_flag()
    assert code == AbcErrorCode.SUCCESS
    assert errors == [0] * 6 and len(brakes) == 6
    realman_emulator.inject("joint_error", joint=2, code=8)
    assert wait_until(lambda: realman_arm.get_error_flag()[1][0][1] == 8)
    assert realman_arm.set_modbus_mode(0, 115200, 2) == AbcErrorCode.SUCCESS
    assert realman_arm.close_modbus_mode(0) == AbcErrorCode.SUCCESS


def test_a_slow_controller_is_an_arm_timeout(realman_arm, realman_emulator):
    # The controller answers 700 ms late: beyond the driver's 500 ms reply timeout.
    realman_emulator.inject("reply_delay", delay_ms=700)
    code, joints = realman_arm.get_joint_degree()
    assert code == AbcErrorCode.ARM_TIMEOUT, realman_arm.last_error
    assert joints == []
    realman_emulator.clear("reply_delay")


def test_callback_rate_and_state_content(realman_arm):
    states = []
    realman_arm.realtime_arm_state_call_back(states.append)
    assert wait_until(lambda: len(states) > 5)
    s = states[-1]
    assert isinstance(s, ArmRealtimeState)
    assert s.name == "left_arm"
    assert abs(s.timestamp - time.time()) < 5
    assert len(s.joint_status.joint_position) == 6
    assert isinstance(s.ee_pose, Pose)
    rate = measure_rate(realman_arm, 1.0)
    print(f"Realman realtime callbacks: {rate:.0f}/s (udp_cycle 1 = 200/s pushed)")
    # 200/s when the machine is idle; a loaded CI runner delivers fewer, never a trickle.
    assert rate > 40


def test_a_callback_may_call_the_arm(realman_arm):
    seen = []

    def cb(state):
        if not seen:
            seen.append(realman_arm.get_joint_degree()[0])

    realman_arm.realtime_arm_state_call_back(cb)
    assert wait_until(lambda: seen, 5)
    assert seen[0] == AbcErrorCode.SUCCESS


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_an_exception_in_the_callback_does_not_stop_the_stream(realman_arm):
    n = []

    def cb(state):
        n.append(1)
        raise ValueError("user bug")

    realman_arm.realtime_arm_state_call_back(cb)
    assert wait_until(lambda: len(n) > 20)


def test_disconnect_while_callbacks_flow_returns(realman_emulator):
    from conftest import connected

    arm = connected("realman", realman_emulator)
    n = []

    def slow(state):
        n.append(state)
        time.sleep(0.002)  # hold the GIL-taking thread busy

    arm.realtime_arm_state_call_back(slow)
    assert wait_until(lambda: len(n) > 10)
    assert returns_within(arm.disconnect, 10)
    # States received before the disconnect may still be in the callback's queue; after
    # them the stream stops.
    assert stops_growing(n)  # the stream stopped with the link
    assert arm.get_joint_degree()[0] == AbcErrorCode.NOT_INITIALIZED


def test_calls_before_connect_are_not_initialized(realman_emulator):
    arm = ArmFactory.create_arm("realman", "a", realman_emulator.params)
    assert arm.get_joint_degree()[0] == AbcErrorCode.NOT_INITIALIZED
    assert arm.move_joint_position(TARGET_DEG, 50, 0, 0, 1) == AbcErrorCode.NOT_INITIALIZED


def free_udp_port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def latest_state(arm, timeout_s: float = 3.0):
    """The first realtime state `arm` delivers within `timeout_s` (None if none)."""
    states = []
    arm.realtime_arm_state_call_back(states.append)
    wait_until(lambda: len(states) > 0, timeout_s)
    arm.realtime_arm_state_call_back(None)
    return states[-1] if states else None


def test_two_controllers_on_one_push_port_each_arm_sees_its_own():
    """A bimanual setup: two controllers aimed at one local UDP port in one process. Before,
    the second create_arm/connect failed with ARM_DATA_RECEIVE_FAILED (the first arm held the
    port); now they share it and each arm gets its own controller's state."""
    import armhil.sim

    udp_port = str(free_udp_port())
    with armhil.sim.realman(initial_joints_deg=[10, 0, 0, 0, 0, 0]) as left_emu, \
            armhil.sim.realman(initial_joints_deg=[-20, 0, 0, 0, 0, 0]) as right_emu:
        arms = []
        for name, emu in (("left_arm", left_emu), ("right_arm", right_emu)):
            params = dict(emu.params)
            params["udp_port"] = udp_port
            arm = ArmFactory.create_arm("realman", name, params)
            assert arm is not None, ArmFactory.last_error()
            assert arm.connect() == AbcErrorCode.SUCCESS, arm.last_error
            arms.append(arm)
        try:
            for arm, j1 in zip(arms, (10.0, -20.0)):
                s = latest_state(arm)
                assert s is not None, f"{arm.name}: no realtime state"
                assert abs(s.joint_status.joint_position[0] - j1) < 0.1, (arm.name, s)
            # A move of one arm shows in its own state only.
            assert arms[1].move_joint_position([-20, 30, 0, 0, 0, 0], 50, 0, 0, 1) == AbcErrorCode.SUCCESS
            assert abs(latest_state(arms[1]).joint_status.joint_position[1] - 30) < 0.1
            assert abs(latest_state(arms[0]).joint_status.joint_position[1]) < 0.1
        finally:
            for arm in arms:
                arm.disconnect()


def test_two_arms_of_one_controller_share_the_push_port():
    """Two arm objects on one controller and one local UDP port: both connect and both get the
    controller's push (the same datagrams)."""
    import armhil.sim

    udp_port = str(free_udp_port())
    with armhil.sim.realman(initial_joints_deg=[0, 15, 0, 0, 0, 0]) as emu:
        params = dict(emu.params)
        params["udp_port"] = udp_port
        arms = [ArmFactory.create_arm("realman", n, params) for n in ("left_arm", "right_arm")]
        try:
            for arm in arms:
                assert arm is not None, ArmFactory.last_error()
                assert arm.connect() == AbcErrorCode.SUCCESS, arm.last_error
            for arm in arms:
                s = latest_state(arm)
                assert s is not None and abs(s.joint_status.joint_position[1] - 15) < 0.1
        finally:
            for arm in arms:
                if arm is not None:
                    arm.disconnect()
