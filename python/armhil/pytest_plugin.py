"""pytest fixtures (registered through the ``pytest11`` entry point when armhil is installed):

- ``realman_emulator``: a running Realman emulator; ``realman_emulator.params`` is the
  ``params`` dict of ``ArmFactory.create_arm("realman", name, params)``.
- ``piper_emulator``: a running Piper emulator behind a socketcand server;
  ``piper_emulator.params`` is the dict of ``ArmFactory.create_arm("piper", name, params)``.

Each test gets a fresh emulator (function scope), stopped after the test.
"""

from typing import Iterator

import pytest

import armhil.sim
from armhil.sim import PiperEmulator, RealmanEmulator


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
