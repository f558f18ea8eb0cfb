"""Emulators running in this process in real time, started as ``armhil sim <device>`` starts
them. Each is a context manager (the emulator stops at the end of the ``with`` block):

    with armhil.sim.realman() as emu:
        arm = ArmFactory.create_arm("realman", "left_arm", emu.params)

Faults use each emulator's own names and its fault table's arguments, by keyword, on every
kind: ``emu.inject("reply_delay", delay_ms=600)`` on the Realman, ``emu.inject("comm_loss",
joint=3)`` on the Piper, ``emu.inject("encoder_glitch", motor=3, counts=100)`` on RobStride
actuators, ``emu.inject("over_voltage", motor=1, voltage_v=40)`` on Damiao motors, then
``emu.clear(...)``; ``emu.faults()`` lists them.

A whole robot from its robot file, every bus a channel of one socketcand server:

    with armhil.sim.robot("robots/humanoid.yaml") as robot:
        bus = can.Bus(interface="socketcand", host=robot.host, port=robot.port, channel="can2")
        robot.inject("over_temperature", joint="left_knee")
        robot.bus_lost("can0")
"""

import os
from typing import List, Optional, Sequence, Union

from armhil._armhil import (
    DamiaoEmulator,
    PiperEmulator,
    RealmanEmulator,
    RobotEmulator,
    RobstrideEmulator,
    sim_damiao as _damiao,
    sim_piper as _piper,
    sim_realman as _realman,
    sim_robot as _robot,
    sim_robstride as _robstride,
)

__all__ = [
    "DamiaoEmulator",
    "PiperEmulator",
    "RealmanEmulator",
    "RobotEmulator",
    "RobstrideEmulator",
    "damiao",
    "piper",
    "realman",
    "robot",
    "robstride",
]


def realman(
    port: int = 0,
    host: str = "127.0.0.1",
    model: str = "RM65-B",
    firmware: str = "V1.7.0",
    initial_joints_deg: Optional[Sequence[float]] = None,
    gripper: bool = True,
) -> RealmanEmulator:
    """A Realman controller on TCP ``host:port`` (port 0 = a free port; see ``emu.port``)."""
    joints = None if initial_joints_deg is None else [float(j) for j in initial_joints_deg]
    return _realman(port, host, model, firmware, joints, gripper)


def piper(
    iface: Optional[str] = None,
    socketcand: str = "127.0.0.1:0",
    firmware: str = "S-V1.8-2",
    initial_joints_deg: Optional[Sequence[float]] = None,
) -> PiperEmulator:
    """A Piper on SocketCAN ``iface``, or (default) behind a socketcand server on
    ``socketcand`` (HOST:PORT, port 0 = a free port; see ``emu.host`` / ``emu.port``)."""
    joints = None if initial_joints_deg is None else [float(j) for j in initial_joints_deg]
    return _piper(iface, socketcand, firmware, joints)


def robstride(
    motors: Optional[List[str]] = None,
    iface: Optional[str] = None,
    socketcand: str = "127.0.0.1:0",
) -> RobstrideEmulator:
    """RobStride actuators (``motors``: "ID:MODEL" strings, default ``["127:RS03"]``) on
    SocketCAN ``iface`` or (default) behind a socketcand server."""
    return _robstride(motors, iface, socketcand)


def damiao(
    motors: Optional[List[str]] = None,
    iface: Optional[str] = None,
    socketcand: str = "127.0.0.1:0",
) -> DamiaoEmulator:
    """Damiao (DM) joint motors (``motors``: "ESC_ID:MODEL" strings answering on ESC_ID + 0x10
    as on the OpenArm, or "ESC_ID:MODEL:FEEDBACK_ID"; default ``["1:DM4310"]``) on SocketCAN
    ``iface`` or (default) behind a socketcand server (HOST:PORT, port 0 = a free port; see
    ``emu.host`` / ``emu.port``). A bad motor string raises ``ValueError``."""
    return _damiao(motors, iface, socketcand)


def robot(
    file: Union[str, "os.PathLike[str]"],
    socketcand: str = "127.0.0.1:0",
    interfaces: bool = False,
    state_file: Optional[Union[str, "os.PathLike[str]"]] = None,
    gantry: Optional[str] = None,
) -> RobotEmulator:
    """A whole robot from its robot file (``armhil sim robot FILE``): one physics world, the
    actuator the file names (RobStride, Damiao) on each actuated joint, every bus served at once — as channels of one
    socketcand server on ``socketcand`` (HOST:PORT, port 0 = a free port; see ``emu.host`` /
    ``emu.port``, channels ``emu.buses``), or with ``interfaces=True`` each on the SocketCAN
    interface of its name. A floating robot hangs on its gantry (``gantry``: ``"until_enabled"``,
    the default unless the robot file says, ``"until_released"`` — see ``release_gantry()`` —
    or ``"off"``). A bad robot file raises ``ValueError`` naming file:line:column; one that
    cannot be read, ``OSError``."""
    return _robot(
        os.fspath(file),
        socketcand,
        interfaces,
        None if state_file is None else os.fspath(state_file),
        gantry,
    )
