"""Piper faults from Python go through the emulator's one fault builder: what a scenario file
refuses is refused here too, with the same message."""

import pytest

import armhil.sim


def test_a_refused_fault_value_gives_the_scenario_message():
    with armhil.sim.piper() as emu:
        # A negative bus voltage used to be accepted here; scenario files refuse it.
        with pytest.raises(ValueError, match=r"^`voltage_v` must be between 0 and 60, got -1$"):
            emu.inject("under_voltage", voltage_v=-1)
        with pytest.raises(ValueError, match=r"^`stall` takes no `temp_c` \(it takes: joint\)$"):
            emu.inject("stall", joint=1, temp_c=3)
        with pytest.raises(ValueError, match="no Piper fault `reply_delay`"):
            emu.inject("reply_delay", delay_ms=1)
        emu.inject("external_torque", joint=2, torque_nm=1.5)
        emu.clear("external_torque", joint=2)  # clearing needs the site, not the value
