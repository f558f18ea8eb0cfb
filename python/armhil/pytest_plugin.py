"""pytest fixtures (registered through the ``pytest11`` entry point when armhil is installed):

- ``realman_emulator``: a running Realman emulator; ``realman_emulator.params`` is the
  ``params`` dict of ``ArmFactory.create_arm("realman", name, params)``.
- ``piper_emulator``: a running Piper emulator behind a socketcand server;
  ``piper_emulator.params`` is the dict of ``ArmFactory.create_arm("piper", name, params)``.

- ``robot_emulator``: starts whole robots: ``robot_emulator("robots/humanoid.yaml")`` returns
  a running ``RobotEmulator`` (keyword arguments as ``armhil.sim.robot``); its buses are
  channels ``robot.buses`` of the socketcand server at ``robot.host``:``robot.port``.

Each test gets fresh emulators (function scope), stopped after the test.
"""

from typing import Any, Callable, Iterator, List

import pytest

import armhil.sim
from armhil.sim import PiperEmulator, RealmanEmulator, RobotEmulator


@pytest.fixture
def realman_emulator() -> Iterator[RealmanEmulator]:
    """A Realman controller emulator on a free local TCP port."""
    with armhil.sim.realman() as emu:
        yield emu


@pytest.fixture
def piper_emulator() -> Iterator[PiperEmulator]:
    """A Piper emulator behind a socketcand server on a free local port."""
    with armhil.sim.piper() as emu:
        yield emu


@pytest.fixture
def robot_emulator() -> Iterator[Callable[..., RobotEmulator]]:
    """Starts whole robots from robot files; every robot started is stopped after the test."""
    started: List[RobotEmulator] = []

    def start(file: Any, **kwargs: Any) -> RobotEmulator:
        robot = armhil.sim.robot(file, **kwargs)
        started.append(robot)
        return robot

    yield start
    for robot in started:
        robot.stop()
