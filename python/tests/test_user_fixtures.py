"""How a user's own tests look: only the plugin's fixtures, no hardware, no armhil.sim."""

from armhil import AbcErrorCode, ArmFactory


def test_my_realman_pick(realman_emulator):
    arm = ArmFactory.create_arm("realman", "left_arm", realman_emulator.params)
    assert arm.connect() == AbcErrorCode.SUCCESS
    assert arm.move_joint_position([0, 20, 70, 0, 90, 0], 50, 0, 0, 1) == AbcErrorCode.SUCCESS
    assert arm.set_gripper_pick(500, 300, True, 5) == AbcErrorCode.SUCCESS
    code, joints = arm.get_joint_degree()
    assert code == AbcErrorCode.SUCCESS and abs(joints[2] - 70) < 0.1
    arm.disconnect()


def test_my_piper_move(piper_emulator):
    arm = ArmFactory.create_arm("piper", "right_arm", piper_emulator.params)
    assert arm.connect() == AbcErrorCode.SUCCESS
    assert arm.move_joint_position([0, 30, -30, 0, 0, 0], 50, 0, 0, 1) == AbcErrorCode.SUCCESS
    code, joints = arm.get_joint_degree()
    assert code == AbcErrorCode.SUCCESS and abs(joints[1] - 30) < 0.3
    arm.disconnect()
