"""`docs/dbc/piper.dbc` read by cantools gives the values `armhil decode` (the driver's codec)
prints, frame by frame, on a bus log recorded from a scenario.

Run (after `cargo build -p armhil`):

    pip install cantools==45.1.0 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_dbc_cantools.py
"""

import os
import subprocess
from pathlib import Path

import pytest

from armhil_process import BIN, require_binary

if os.environ.get("CI"):
    # In CI cantools is installed by .ci/run: missing is a failure, not a skip.
    import cantools
else:
    cantools = pytest.importorskip("cantools")

REPO = Path(__file__).resolve().parents[2]
DBC = REPO / "docs" / "dbc" / "piper.dbc"
SCENARIO = REPO / "scenarios" / "piper" / "move_j_basic.yaml"


def parse_decode_line(line):
    """`t  id  name  key=value [unit]  …` → (id, name, {key: value})."""
    parts = line.split("  ")
    ident, name = int(parts[1], 16), parts[2]
    fields = {}
    for part in parts[3:]:
        if "=" not in part:
            continue
        key, value = part.split("=", 1)
        fields[key] = value.split(" ")[0]
    return ident, name, fields


def read_candump(path):
    frames = []
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        ident, data = line.split()[2].split("#", 1)
        frames.append((int(ident, 16), bytes.fromhex(data)))
    return frames


@pytest.fixture(scope="module")
def recorded_log(tmp_path_factory):
    require_binary()
    out = tmp_path_factory.mktemp("run")
    result = subprocess.run(
        [BIN, "run", str(SCENARIO), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    logs = list(out.rglob("bus.log"))
    assert len(logs) == 1, logs
    return logs[0]


def test_cantools_and_armhil_decode_agree(recorded_log):
    db = cantools.database.load_file(str(DBC))
    decoded = subprocess.run(
        [BIN, "decode", str(recorded_log)], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    frames = read_candump(recorded_log)
    assert len(decoded) == len(frames)
    known = {m.frame_id for m in db.messages}
    compared = {}
    for line, (ident, data) in zip(decoded, frames):
        got_id, name, ours = parse_decode_line(line)
        assert got_id == ident, line
        if ident not in known:
            continue
        message = db.get_message_by_frame_id(ident)
        assert name == message.name, line
        theirs = message.decode(data, decode_choices=True)
        assert set(theirs) == set(ours), (line, theirs)
        for key, value in theirs.items():
            if isinstance(value, (int, float)):
                assert float(ours[key]) == pytest.approx(float(value), abs=1e-9), (line, key)
            else:
                assert ours[key] == str(value), (line, key, value)
        compared[message.name] = compared.get(message.name, 0) + 1
    # Joint angles, status, driver feedback and the host's joint targets all took part.
    for name in ["ArmStatus", "JointFeedback12", "JointFeedback56", "DriverHighSpeed3",
                 "DriverLowSpeed6", "EndPoseXY", "JointCtrl12"]:
        assert compared.get(name, 0) > 0, (name, compared)
    assert sum(compared.values()) > 500, compared


def test_a_moving_joint_reads_the_same_in_both(recorded_log):
    """Spot check on values that change: J1's angle over the move, not just zeros."""
    db = cantools.database.load_file(str(DBC))
    angles = set()
    for ident, data in read_candump(recorded_log):
        if ident == 0x2A5:
            angles.add(round(db.decode_message(ident, data)["J1_angle"], 3))
    assert len(angles) > 10, sorted(angles)[:20]
