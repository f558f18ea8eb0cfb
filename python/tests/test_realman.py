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
