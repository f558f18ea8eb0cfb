"""Several devices in one process: `armhil sim rig FILE` serving two Realman controllers
and a Piper leader/follower pair, reached by the vendors' clients unchanged — one Python
program holding two Robotic_Arm handles (a dual-arm robot's program), and python-can on each
Piper's socketcand server.

Run (after `cargo build -p armhil`):

    pip install Robotic_Arm==1.1.6 python-can==4.6.1 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_sim_rig.py
"""

import os
import time

import pytest

from armhil_process import accepts, free_port, listening

if os.environ.get("CI"):
    # In CI both are installed by .ci/run: a missing package is a failure, not a skip.
    import can
    import Robotic_Arm.rm_robot_interface as sdk
else:
    can = pytest.importorskip("can")
    sdk = pytest.importorskip("Robotic_Arm.rm_robot_interface")


def wait_listening(port, timeout_s=20):
    deadline = time.monotonic() + timeout_s
    while not accepts(port):
        if time.monotonic() > deadline:
            pytest.fail(f"nothing listens on {port} after {timeout_s} s")
        time.sleep(0.05)


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """One `armhil sim rig` process; yields the ports by device name."""
    ports = {name: free_port() for name in ["left", "right", "leader", "follower"]}
    file = tmp_path_factory.mktemp("rig") / "rig.yaml"
    file.write_text(
        f"""devices:
  left: {{kind: realman, port: {ports['left']}}}
  right: {{kind: realman, port: {ports['right']}, model: RM75-B}}
  leader: {{kind: piper, socketcand: {ports['leader']}, role: leader}}
  follower: {{kind: piper, socketcand: {ports['follower']}}}
"""
    )
    with listening(["sim", "rig", str(file)], ports["left"]) as proc:
        for port in ports.values():
            wait_listening(port)
        yield ports
    assert proc.returncode == 0, f"rig exit {proc.returncode}: {proc.stderr_tail}"


def connect(port):
    robot = sdk.RoboticArm(sdk.rm_thread_mode_e.RM_TRIPLE_MODE_E)
    handle = robot.rm_create_robot_arm("127.0.0.1", port)
    assert handle.id >= 1, f"the SDK's handshake with port {port} failed"
    return robot


def test_one_program_drives_two_realman_arms_independently(rig):
    left, right = connect(rig["left"]), connect(rig["right"])
    try:
        assert left.rm_get_arm_software_info()[1]["product_version"] == "RM65-B"
        assert right.rm_get_arm_software_info()[1]["product_version"] == "RM75-B"
        right_before = right.rm_get_current_arm_state()[1]["joint"]
        target = [15.0, 10.0, 20.0, 0.0, 30.0, 0.0]
        assert left.rm_movej(target, 50, 0, 0, 1) == 0
        assert left.rm_get_current_arm_state()[1]["joint"][:6] == pytest.approx(target, abs=0.05)
        # The other controller is another arm: it did not move.
        assert right.rm_get_current_arm_state()[1]["joint"] == pytest.approx(right_before, abs=0.01)
        assert len(right_before) == 7, "an RM75 has seven joints"
    finally:
        left.rm_delete_robot_arm()
        right.rm_delete_robot_arm()


def ids_heard(port, seconds=0.5):
    with can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0") as bus:
        heard = set()
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            msg = bus.recv(timeout=0.1)
            if msg is not None:
                heard.add(msg.arbitration_id)
        return heard


def test_each_piper_answers_on_its_own_server_in_its_role(rig):
    leader, follower = ids_heard(rig["leader"]), ids_heard(rig["follower"])
    # A leader (teach-input arm) sends its joints as commands (0x155-0x157); a follower
    # reports them as feedback (0x2A5-0x2A7). Neither hears the other's bus.
    assert {0x155, 0x156, 0x157} <= leader, sorted(map(hex, leader))
    assert not any(0x2A1 <= i <= 0x2A8 for i in leader), sorted(map(hex, leader))
    assert {0x2A5, 0x2A6, 0x2A7} <= follower, sorted(map(hex, follower))
    assert not ({0x155, 0x156, 0x157} & follower), sorted(map(hex, follower))
