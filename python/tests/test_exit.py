"""The interpreter exits cleanly while realtime callbacks are flowing and nothing was
disconnected or stopped (a driver thread inside Python at finalization would abort)."""

import subprocess
import sys

SCRIPT = """
import time, armhil
from armhil import ArmFactory
emu = armhil.sim.realman()
arm = ArmFactory.create_arm("realman", "a", emu.params)
assert arm.connect() == 0
arm.realtime_arm_state_call_back(lambda s: time.sleep(0.001))
emu2 = armhil.sim.piper()
arm2 = ArmFactory.create_arm("piper", "p", emu2.params)
assert arm2.connect() == 0
arm2.realtime_arm_state_call_back(lambda s: None)
time.sleep(0.3)
print("bye")
"""


def test_exit_with_callbacks_flowing_is_clean():
    for _ in range(3):
        out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                             timeout=60)
        assert out.returncode == 0, out.stderr
        assert out.stdout.strip() == "bye"
