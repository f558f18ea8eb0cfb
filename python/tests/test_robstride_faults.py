"""RobStride faults from Python go through the emulator's one fault builder: the same names,
CAN ID range and messages as scenario files."""

import pytest

import armhil.sim


def test_a_can_id_out_of_range_is_refused_with_the_scenario_message():
    with armhil.sim.robstride(motors=["1:RS03"]) as emu:
        with pytest.raises(ValueError, match=r"^`motor`: CAN ID 128 out of range, expected 1\.\.=127$"):
            emu.inject("over_temperature", 128)
        with pytest.raises(ValueError, match=r"^`motor`: CAN ID 0 out of range"):
            emu.clear("over_temperature", 0)
        with pytest.raises(ValueError, match=r"^no RobStride fault `melted`; known: over_temperature, "):
            emu.inject("melted", 1)
        assert all(m["fault_word"] == 0 for m in emu.state())
