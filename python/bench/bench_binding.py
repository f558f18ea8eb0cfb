"""Binding overhead and callback rate of the armhil extension (prints figures; not a test).

Build the extension in release first (the dev build is several times slower):

    cd python && maturin develop --release && python bench/bench_binding.py

- Per-call overhead: `forward_kinematics` on a connected arm does no I/O (the kinematic
  chain is client-side), so its time per call is the binding's cost (argument conversion,
  GIL release, a block_on on the driver runtime, result conversion) plus the solver's.
  A no-op call (`arm.name`) and an error return before any work (`v = 0`) bound it below.
- Callback rate: realtime states delivered to a Python callback per second.
- Emulators at rest: the process's CPU (% of one core) while each in-process emulator runs
  with no client, 1 s after it started, over 5 s — the figure `cargo bench --bench
  wire_latency` prints for `armhil sim`. The emulators share one runtime worker, as there.
"""

import os
import statistics
import time
import timeit

import armhil.sim
from armhil import AbcErrorCode, ArmFactory


def per_call_us(fn, number: int = 20000, repeat: int = 5) -> float:
    """Best-of-`repeat` mean time per call, microseconds."""
    times = timeit.repeat(fn, number=number, repeat=repeat)
    return min(times) / number * 1e6


def callback_rate(arm, seconds: float = 3.0) -> float:
    stamps = []
    arm.realtime_arm_state_call_back(lambda s: stamps.append(time.perf_counter()))
    time.sleep(0.3)
    start = len(stamps)
    time.sleep(seconds)
    n = len(stamps) - start
    arm.realtime_arm_state_call_back(None)
    gaps = [b - a for a, b in zip(stamps[start:], stamps[start + 1 :])]
    if gaps:
        print(f"  callback period: median {statistics.median(gaps) * 1e3:.2f} ms, "
              f"max {max(gaps) * 1e3:.2f} ms")
    return n / seconds


def bench(arm_type: str, emu) -> None:
    arm = ArmFactory.create_arm(arm_type, "bench", emu.params)
    assert arm is not None and arm.connect() == AbcErrorCode.SUCCESS, arm.last_error
    joints = [10.0, 20.0, -30.0, 0.0, 20.0, 0.0]
    assert arm.forward_kinematics(joints)[0] == AbcErrorCode.SUCCESS
    print(f"{arm_type}:")
    print(f"  arm.name (attribute, no runtime):      {per_call_us(lambda: arm.name):6.2f} us")
    print(f"  move_joint_position(v=0) (code only):  "
          f"{per_call_us(lambda: arm.move_joint_position(joints, 0, 0, 0, 1)):6.2f} us")
    print(f"  forward_kinematics (no I/O):           "
          f"{per_call_us(lambda: arm.forward_kinematics(joints)):6.2f} us  (target <= 5 us)")
    print(f"  get_joint_degree (I/O or cached):      "
          f"{per_call_us(lambda: arm.get_joint_degree(), number=200):6.2f} us")
    print(f"  realtime callbacks: {callback_rate(arm):.0f}/s")
    arm.disconnect()


def cpu_at_rest(label: str, start, warm_up_s: float = 1.0, seconds: float = 5.0) -> None:
    """Prints the process's CPU while the emulator `start()` returns runs with no client."""
    with start():
        time.sleep(warm_up_s)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        time.sleep(seconds)
        cpu1, wall1 = time.process_time(), time.perf_counter()
    print(f"  {label}: {100 * (cpu1 - cpu0) / (wall1 - wall0):.1f} % of a core at rest")


def main() -> None:
    with armhil.sim.realman() as emu:
        bench("realman", emu)
    with armhil.sim.piper() as emu:
        bench("piper", emu)
    print("emulators in this process, no client:")
    cpu_at_rest("realman", armhil.sim.realman)
    cpu_at_rest("piper", armhil.sim.piper)
    five = ["1:RS03", "2:RS03", "3:RS02", "4:RS02", "5:RS04"]
    cpu_at_rest("robstride (5 motors)", lambda: armhil.sim.robstride(five))
    cpu_at_rest("damiao (one DM4310)", lambda: armhil.sim.damiao(["1:DM4310"]))
    humanoid = os.path.join(os.path.dirname(__file__), "..", "..", "robots", "humanoid.yaml")
    cpu_at_rest("robot humanoid.yaml", lambda: armhil.sim.robot(humanoid))


if __name__ == "__main__":
    main()
