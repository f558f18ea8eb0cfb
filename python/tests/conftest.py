"""Shared helpers of the armhil test suite (the emulator fixtures come from the installed
plugin, armhil.pytest_plugin, as they would for a user)."""

import threading
import time
from typing import Callable, List

import pytest

from armhil import AbcErrorCode, ArmFactory, ArmInterface

# A reachable joint target for both arms (degrees), inside every joint's limits.
TARGET_DEG = [10.0, 20.0, -30.0, 0.0, 20.0, 0.0]


def wait_until(cond: Callable[[], bool], timeout_s: float = 5.0) -> bool:
    """Polls `cond` until true or the timeout."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return cond()


def connected(arm_type: str, emu, name: str = "arm") -> ArmInterface:
    arm = ArmFactory.create_arm(arm_type, name, emu.params)
    assert arm is not None, ArmFactory.last_error()
    code = arm.connect()
    assert code == AbcErrorCode.SUCCESS, arm.last_error
    return arm


def measure_rate(arm: ArmInterface, seconds: float = 1.0) -> float:
    """Realtime callbacks per second over `seconds`."""
    stamps: List[float] = []
    arm.realtime_arm_state_call_back(lambda s: stamps.append(time.monotonic()))
    time.sleep(0.2)  # let the stream settle
    start = len(stamps)
    time.sleep(seconds)
    n = len(stamps) - start
    arm.realtime_arm_state_call_back(None)
    return n / seconds


def stops_growing(items: list, quiet_s: float = 0.3, timeout_s: float = 5.0) -> bool:
    """Whether `items` stops growing (no new entry for `quiet_s`) within `timeout_s`."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        before = len(items)
        time.sleep(quiet_s)
        if len(items) == before:
            return True
    return False


def returns_within(fn: Callable[[], object], timeout_s: float) -> bool:
    """Runs `fn` on a thread; whether it returned within `timeout_s` (no deadlock)."""
    t = threading.Thread(target=fn, daemon=True)
    t.start()
    t.join(timeout_s)
    return not t.is_alive()


@pytest.fixture
def realman_arm(realman_emulator):
    arm = connected("realman", realman_emulator, "left_arm")
    yield arm
    arm.disconnect()


@pytest.fixture
def piper_arm(piper_emulator):
    arm = connected("piper", piper_emulator, "right_arm")
    yield arm
    arm.disconnect()
