"""The older Realman Python SDK generation (the `Arm` class of `robotic-arm-package` 4.3.6,
unchanged) against `armhil sim realman`: IO ports, supplies and the software version.

Before, each of these calls waited 3 s and returned `7: SOCKET_TIME_OUT` (the emulator did not
answer the commands). The `Arm` class always connects to port 8080, so the emulator listens on
127.0.0.1 + a loopback alias (127.0.0.x:8080), which Linux routes without setup.

Run (after `cargo build -p armhil`):

    pip install robotic-arm-package==4.3.6 pytest   (.ci/run installs it)
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_realman_arm_class.py
"""

import contextlib
import os
import signal
import socket
import subprocess
import time

import pytest

from armhil_process import BIN, require_binary

if os.environ.get("CI"):
    # In CI .ci/run installs the SDK: a missing SDK is a failure, not a skip.
    import robotic_arm_package.robotic_arm as ra
else:
    ra = pytest.importorskip(
        "robotic_arm_package.robotic_arm",
        reason="robotic-arm-package 4.3.6 (the Arm-class SDK) is not installed",
    )

ADDRESS = "127.0.0.73"


@contextlib.contextmanager
def emulator_on_8080(address):
    require_binary()
    with socket.socket() as probe:
        try:
            probe.bind((address, 8080))
        except OSError:
            pytest.skip(f"{address}:8080 is taken")
    proc = subprocess.Popen(
        [BIN, "sim", "realman", "--bind", address, "--port", "8080"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 20
    while True:
        try:
            socket.create_connection((address, 8080), timeout=0.2).close()
            break
        except OSError:
            if proc.poll() is not None or time.monotonic() > deadline:
                proc.kill()
                pytest.fail(f"emulator did not start: {proc.stderr.read()}")
            time.sleep(0.05)
    try:
        yield proc
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()


@pytest.fixture(scope="module")
def arm():
    with emulator_on_8080(ADDRESS):
        robot = ra.Arm(ra.RM65, ADDRESS)
        assert robot.Arm_Socket_State() == 0
        yield robot
        robot.Arm_Socket_Close()


def test_software_version_decodes_the_version_codes(arm):
    code, plan, ctrl, kernel1, kernel2, product = arm.Get_Arm_Software_Version()
    assert code == 0
    assert (plan, ctrl, kernel1, kernel2, product) == ("6B0170", "6B0170", "203", "203", "RM65-B")


def test_controller_io_round_trips(arm):
    assert arm.Set_IO_Mode(1, 1) == 0
    assert arm.Set_DO_State(1, True) == 0
    assert arm.Get_IO_State(1) == (0, 1, 1), "level high, mode output"
    assert arm.Set_AO_State(1, 5.0) == 0, "5 V"
    code, do, ao = arm.Get_IO_Output()
    assert code == 0 and do[0] == 1 and ao[0] == pytest.approx(5.0), (do, ao)
    code, di, ai = arm.Get_IO_Input()
    assert code == 0 and di == [0, 0, 0, 0] and ai == [0.0] * 4
    assert arm.Set_Voltage(2) == 0
    assert arm.Get_Voltage() == 2, "the Arm class returns the type alone"


def test_tool_io_and_voltage_round_trip(arm):
    assert arm.Set_Tool_Voltage(2) == 0
    assert arm.Get_Tool_Voltage() == (0, 2)
    assert arm.Set_Tool_IO_Mode(2, 1) == 0
    assert arm.Set_Tool_DO_State(2, True) == 0
    code, modes, levels = arm.Get_Tool_IO_State()
    assert code == 0 and modes == [0.0, 1.0] and levels == [0.0, 1.0]


def test_refusals_come_back_as_controller_false(arm):
    assert arm.Set_IO_Mode(2, 0) == 0
    assert arm.Set_DO_State(2, True) == "1: CONTROLLER_DATA_RETURN_FALSE", "an input port"
