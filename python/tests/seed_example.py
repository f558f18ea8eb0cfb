"""A robot script written only from the Arm API document (no knowledge of armhil's
internals): create from a configuration file, connect, move, read joints, use the gripper,
receive the realtime state. Usage: python seed_example.py arm.json"""

import sys
import time

from armhil import AbcErrorCode, ArmFactory

config_path = sys.argv[1]

arm = ArmFactory.create_arm_from_config(config_path)
assert arm is not None, "creation failed"

ret = arm.connect()
assert ret == AbcErrorCode.SUCCESS, ret

states = []


def on_state(state):
    states.append(state)


arm.realtime_arm_state_call_back(on_state)

target = [0.0, 20.0, 70.0, 0.0, 90.0, 0.0]
ret = arm.move_joint_position(target, 50, 0, 0, 1)
assert ret == AbcErrorCode.SUCCESS, ret

ret, joints = arm.get_joint_degree()
assert ret == AbcErrorCode.SUCCESS, ret
assert len(joints) == len(target)
assert all(abs(j - t) < 0.1 for j, t in zip(joints, target)), joints
print("joints:", joints)

ret = arm.set_gripper_release(500, True, 5)
assert ret == AbcErrorCode.SUCCESS, ret
ret = arm.set_gripper_pick(500, 200, True, 5)
assert ret == AbcErrorCode.SUCCESS, ret
ret, gripper = arm.get_gripper_state()
assert ret == AbcErrorCode.SUCCESS, ret
assert gripper.status == 1
assert 0 <= gripper.actpos <= 1000
print("gripper:", gripper.mode, gripper.actpos)

time.sleep(0.5)
assert len(states) > 0
last = states[-1]
assert last.name == arm.name
assert len(last.joint_status.joint_position) == len(target)
assert all(abs(j - t) < 0.1 for j, t in zip(last.joint_status.joint_position, target))
print("realtime states:", len(states))

arm.disconnect()
print("OK")
