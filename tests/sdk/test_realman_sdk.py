"""The vendor's Python SDK (Robotic_Arm 1.1.6, unchanged) against `armhil sim realman`.

Run (after `cargo build -p armhil`):

    pip install Robotic_Arm==1.1.6 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_realman_sdk.py

The emulator is started on a free 127.0.0.1 port for this module and stopped with SIGINT at the
end. Every SDK call below is what a user's program would make; nothing is patched.
"""

import json
import math
import os
import socket
import threading
import time

import pytest

from armhil_process import free_port, listening

if os.environ.get("CI"):
    # In CI the SDK is installed by .ci/run: a missing SDK is a failure, not a skip.
    import Robotic_Arm.rm_robot_interface as sdk
else:
    sdk = pytest.importorskip("Robotic_Arm.rm_robot_interface")

# ctypes callbacks handed to the SDK (freeing one the SDK still calls crashes the process).
KEEP_ALIVE = []


@pytest.fixture(scope="module")
def emulator():
    """`armhil sim realman` on a free port; yields the port."""
    port = free_port()
    with listening(["sim", "realman", "--bind", "127.0.0.1", "--port", str(port)], port):
        yield port


@pytest.fixture(scope="module")
def arm(emulator):
    """One SDK handle in triple mode (TCP + event thread + UDP push thread)."""
    robot = sdk.RoboticArm(sdk.rm_thread_mode_e.RM_TRIPLE_MODE_E)
    handle = robot.rm_create_robot_arm("127.0.0.1", emulator)
    assert handle.id >= 1, "the SDK's 11-query handshake failed"
    yield robot
    # Only a handle that connected may be deleted: the SDK hangs on a failed one.
    robot.rm_delete_robot_arm()


def joints(robot):
    code, state = robot.rm_get_current_arm_state()
    assert code == 0
    return state["joint"], state["pose"], state["err"]


def test_handshake_gives_a_handle_and_the_model(arm):
    code, info = arm.rm_get_arm_software_info()
    assert code == 0
    assert info["product_version"] == "RM65-B"


def test_blocking_movej_arrives_at_the_target(arm):
    target = [10.0, 20.0, 30.0, 0.0, 40.0, 0.0]
    assert arm.rm_movej(target, 50, 0, 0, 1) == 0
    q, _, err = joints(arm)
    assert q == pytest.approx(target, abs=0.05)
    assert all(code == "0" for code in err["err"]), err


def test_blocking_movel_arrives_at_the_pose(arm):
    assert arm.rm_movej([0.0, 30.0, 60.0, 0.0, 60.0, 0.0], 50, 0, 0, 1) == 0
    _, pose, _ = joints(arm)
    target = list(pose)
    target[0] += 0.05  # 5 cm along x, same orientation
    assert arm.rm_movel(target, 30, 0, 0, 1) == 0
    _, reached, _ = joints(arm)
    assert reached[:3] == pytest.approx(target[:3], abs=0.001)
    for got, want in zip(reached[3:], target[3:]):
        # Euler angles near ±π may come back with the other sign: compare on the circle.
        assert abs(math.remainder(got - want, 2 * math.pi)) < 0.01, (reached, target)


def test_out_of_limit_movej_is_refused_and_the_arm_stays(arm):
    before, _, _ = joints(arm)
    assert arm.rm_movej([0.0, 200.0, 0.0, 0.0, 0.0, 0.0], 50, 0, 0, 1) == 1
    time.sleep(0.3)
    after, _, err = joints(arm)
    assert after == pytest.approx(before, abs=0.01)
    assert "4098" in err["err"]


def test_realtime_push_reaches_the_callback(arm):
    port = free_port(socket.SOCK_DGRAM)
    custom = sdk.rm_udp_custom_config_t(joint_speed=0, arm_current_status=1)
    config = sdk.rm_realtime_push_config_t(1, True, port, -1, "127.0.0.1", custom)
    assert arm.rm_set_realtime_push(config) == 0
    code, current = arm.rm_get_realtime_push()
    assert code == 0 and current["port"] == port and current["cycle"] == 1
    received = []
    lock = threading.Lock()

    def on_state(data):
        with lock:
            received.append(data.errCode)

    callback = sdk.rm_realtime_arm_state_callback_ptr(on_state)
    # The C library keeps calling it after this test: it must outlive the module.
    KEEP_ALIVE.append(callback)
    arm.rm_realtime_arm_state_call_back(callback)
    time.sleep(0.3)
    with lock:
        received.clear()
    time.sleep(1.0)
    with lock:
        count = len(received)
        codes = set(received)
    # cycle 1 = every 5 ms = 200 per second; allow for scheduling on a busy machine.
    assert count > 120, f"{count} datagrams in 1 s"
    assert codes == {0}, f"callback error codes {codes}"


def test_gripper_blocking_move_and_state(arm):
    assert arm.rm_set_gripper_position(300, True, 5) == 0
    code, state = arm.rm_get_gripper_state()
    assert code == 0 and state["actpos"] == 300


def test_modbus_registers_plus_mode_and_hand_follow(arm):
    """The SDK's own parsers accept our replies: a register written over Modbus RTU reads back
    (signed, as the controller reports it); the end-effector protocol mode round-trips; hand
    angle following is acknowledged."""
    assert arm.rm_set_modbus_mode(0, 115200, 2) == 0
    params = sdk.rm_peripheral_read_write_params_t(port=0, address=100, device=1, num=2)
    assert arm.rm_write_registers(params, [0x12, 0x34, 0xAB, 0xCD]) == 0
    code, value = arm.rm_read_holding_registers(
        sdk.rm_peripheral_read_write_params_t(port=0, address=100, device=1))
    assert (code, value) == (0, 0x1234)
    code, value = arm.rm_read_holding_registers(
        sdk.rm_peripheral_read_write_params_t(port=0, address=101, device=1))
    assert (code, value) == (0, 0xABCD - 0x10000)
    assert arm.rm_close_modbus_mode(0) == 0
    code, _ = arm.rm_read_holding_registers(
        sdk.rm_peripheral_read_write_params_t(port=0, address=100, device=1))
    assert code == 1, "no port in Modbus mode: the controller answers false"
    assert arm.rm_set_rm_plus_mode(256000) == 0
    assert arm.rm_get_rm_plus_mode() == (0, 256000)
    assert arm.rm_set_rm_plus_mode(0) == 0
    # Blocking: the SDK waits for the controller's acknowledgement of hand_follow_angle
    # (before: the command had another name in the emulator, no answer, -2 after 0.5 s).
    assert arm.rm_set_hand_follow_angle([100, 200, 300, 400, 500, 600], True) == 0


def test_hand_follow_pos_reads_the_end_effector_identity_first(arm):
    """rm_set_hand_follow_pos asks get_rm_plus_base_info before it sends; the emulator answers
    with the documented base_info of its hand while the end-effector protocol is on (before:
    no reply, and the SDK refused to send)."""
    assert arm.rm_set_rm_plus_mode(115200) == 0
    code, info = arm.rm_get_rm_plus_base_info()
    assert code == 0 and (info["type"], info["dof"]) == (2, 6), info
    assert arm.rm_set_hand_follow_pos([100, 200, 300, 400, 500, 600], True) == 0
    assert arm.rm_set_rm_plus_mode(0) == 0
    code, _ = arm.rm_get_rm_plus_base_info()
    assert code != 0, "protocol off: no device answers"


def test_io_ports_and_supplies_round_trip(arm):
    """The controller's and the tool's IO through the SDK's own parsers (before: no reply, -2)."""
    assert arm.rm_set_do_state(2, 1) == 1, "port 2 boots as an input"
    assert arm.rm_set_io_mode(2, 1) == 0
    assert arm.rm_set_do_state(2, 1) == 0
    code, state = arm.rm_get_io_state(2)
    assert code == 0 and state["io_state"] == 1 and state["io_config"]["io_mode"] == 1, state
    code, outputs = arm.rm_get_io_output()
    assert code == 0 and outputs[1] == 1, outputs
    code, inputs = arm.rm_get_io_input()
    assert code == 0 and inputs == [0, 0, 0, 0], inputs
    assert arm.rm_set_voltage(2, True) == 0
    assert arm.rm_get_voltage() == (0, 2)
    assert arm.rm_set_tool_voltage(1) == 0
    assert arm.rm_get_tool_voltage() == (0, 1)
    assert arm.rm_set_tool_IO_mode(1, 1) == 0
    assert arm.rm_set_tool_do_state(1, 1) == 0
    tool = arm.rm_get_tool_io_state()
    assert tool["return_code"] == 0 and tool["IO_state"][0] == 1, tool
    # Back to power-on so the other tests see a booted controller.
    assert arm.rm_set_io_mode(2, 0) == 0
    assert arm.rm_set_tool_IO_mode(1, 0) == 0
    assert arm.rm_set_tool_voltage(3) == 0
    assert arm.rm_set_voltage(3, True) == 0


def test_motion_parameters_round_trip(arm):
    assert arm.rm_set_arm_max_line_speed(0.5) == 0
    assert arm.rm_get_arm_max_line_speed() == (0, pytest.approx(0.5))
    assert arm.rm_set_arm_tcp_init() == 0  # wire command set_arm_init
    assert arm.rm_get_arm_max_line_speed() == (0, pytest.approx(0.25))
    assert arm.rm_set_collision_state(3) == 0
    assert arm.rm_get_collision_stage() == (0, 3)


def raw_request(port, payload: bytes, timeout=2.0):
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(payload)
        data = b""
        while b"\r\n" not in data:
            chunk = s.recv(4096)
            if not chunk:
                break
            data += chunk
    return json.loads(data.split(b"\r\n")[0])


def test_raw_socket_pretty_printed_and_unterminated_requests_get_replies(emulator):
    pretty = b'{\n\t"command":\t"get_joint_degree"\n}\r\n'
    assert raw_request(emulator, pretty)["state"] == "joint_degree"
    bare = b'{"command":"get_arm_power_state"}'
    assert raw_request(emulator, bare) == {"state": "arm_power_state", "power_state": 1}
