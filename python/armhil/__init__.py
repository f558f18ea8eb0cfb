"""armhil: a vendor-neutral robot arm API (Realman, Piper) and in-process emulators.

    from armhil import ArmFactory, AbcErrorCode

    arm = ArmFactory.create_arm_from_config("arm.json")
    if arm.connect() == AbcErrorCode.SUCCESS:
        arm.move_joint_position([0, 20, 70, 0, 90, 0], 50, 0, 0, 1)

`armhil.sim` starts emulators (``armhil.sim.realman()``, ``armhil.sim.piper()``) so the same
code runs without hardware; the pytest plugin provides them as fixtures.
"""

from armhil._armhil import (
    AbcErrorCode,
    ArmFactory,
    ArmFactoryParam,
    ArmForceSensor,
    ArmInterface,
    ArmRealtimeState,
    GripperState,
    JointState,
    PeripheralReadWriteParams,
    Pose,
)
from armhil import sim

__all__ = [
    "AbcErrorCode",
    "ArmFactory",
    "ArmFactoryParam",
    "ArmForceSensor",
    "ArmInterface",
    "ArmRealtimeState",
    "GripperState",
    "JointState",
    "PeripheralReadWriteParams",
    "Pose",
    "sim",
]
