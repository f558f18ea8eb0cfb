"""Runs seed_example.py (written from the API document alone) unmodified against the
Realman emulator, with a configuration file in the document's format."""

import json
import os
import subprocess
import sys

import armhil.sim


def test_the_seed_script_runs_against_the_emulator(tmp_path):
    with armhil.sim.realman() as emu:
        config = {
            "arm_type": "realman",
            "arm_name": "left_arm",
            "ip": emu.host,
            "port": str(emu.port),
            "udp_ip": "127.0.0.1",
            "udp_port": "0",
            "udp_cycle": "1",
            "enable_gripper": "false",
        }
        path = tmp_path / "arm.json"
        path.write_text(json.dumps(config, indent=4))
        script = os.path.join(os.path.dirname(__file__), "seed_example.py")
        out = subprocess.run([sys.executable, script, str(path)], capture_output=True,
                             text=True, timeout=120)
        print(out.stdout, out.stderr)
        assert out.returncode == 0, out.stderr
        assert out.stdout.strip().endswith("OK")
        assert abs(emu.joints_deg()[2] - 70.0) < 0.1
