"""RobStride faults from Python go through the emulator's one fault builder: the same names,
CAN ID range and messages as scenario files, as ``inject(name, **kwargs)`` with the fault
table's parameter names (``motor=`` and the fault's own values)."""

import math

import pytest

import armhil.sim

COUNTS_PER_TURN = 16384


def test_a_can_id_out_of_range_is_refused_with_the_scenario_message():
    with armhil.sim.robstride(motors=["1:RS03"]) as emu:
        with pytest.raises(ValueError, match=r"^`motor`: CAN ID 128 out of range, expected 1\.\.=127$"):
            emu.inject("over_temperature", motor=128)
        with pytest.raises(ValueError, match=r"^`motor`: CAN ID 0 out of range"):
            emu.clear("over_temperature", motor=0)
        with pytest.raises(ValueError, match=r"^no RobStride fault `melted`; known: over_temperature, "):
            emu.inject("melted", motor=1)
        with pytest.raises(ValueError, match=r"^`gate_driver` needs `motor`$"):
            emu.inject("gate_driver")
        assert all(m["fault_word"] == 0 for m in emu.state())


def test_an_encoder_glitch_shifts_the_reported_angle_by_its_counts_until_cleared():
    with armhil.sim.robstride(motors=["3:RS03", "4:RS02"]) as emu:
        before = {m["can_id"]: m["angle_rad"] for m in emu.state()}
        emu.inject("encoder_glitch", motor=3, counts=1024)
        assert emu.active_faults == ["encoder_glitch 1024 counts on motor 3"]
        after = {m["can_id"]: m for m in emu.state()}
        shift = 1024 * 2 * math.pi / COUNTS_PER_TURN
        assert after[3]["angle_rad"] - before[3] == pytest.approx(shift, abs=1e-9)
        assert after[4]["angle_rad"] == pytest.approx(before[4], abs=1e-9)
        assert after[3]["fault_word"] == 0, "the firmware cannot tell its encoder lies"
        # Injected again on the same motor, the new size replaces the old.
        emu.inject("encoder_glitch", motor=3, counts=-300)
        assert emu.active_faults == ["encoder_glitch -300 counts on motor 3"]
        shifted = emu.state()[0]["angle_rad"] - before[3]
        assert shifted == pytest.approx(-300 * 2 * math.pi / COUNTS_PER_TURN, abs=1e-9)
        # Clearing names the motor; the size may be left out.
        emu.clear("encoder_glitch", motor=3)
        assert emu.active_faults == []
        assert emu.state()[0]["angle_rad"] == pytest.approx(before[3], abs=1e-9)


def test_a_wrong_keyword_is_refused_by_name():
    with armhil.sim.robstride(motors=["3:RS03"]) as emu:
        with pytest.raises(ValueError, match=r"^fault `encoder_glitch` has no argument `count`; it takes: motor, counts$"):
            emu.inject("encoder_glitch", motor=3, count=100)
        with pytest.raises(ValueError, match=r"^fault `gate_driver` has no argument `volts`; it takes: motor$"):
            emu.clear("gate_driver", motor=3, volts=3)
        with pytest.raises(ValueError, match=r"^`encoder_glitch` needs `counts`$"):
            emu.inject("encoder_glitch", motor=3)
        with pytest.raises(ValueError, match=r"^`counts`: encoder counts 9000 out of range, expected -8192\.\.=8192$"):
            emu.inject("encoder_glitch", motor=3, counts=9000)
        assert emu.active_faults == []


def test_the_old_positional_can_id_still_works_with_a_deprecation_warning():
    with armhil.sim.robstride(motors=["3:RS03"]) as emu:
        with pytest.warns(DeprecationWarning, match=r"`can_id` is the old spelling of `motor=`"):
            emu.inject("gate_driver", 3)
        assert emu.active_faults == ["gate_driver on motor 3"]
        with pytest.warns(DeprecationWarning):
            emu.inject("encoder_glitch", 3, counts=10)
        with pytest.warns(DeprecationWarning):
            emu.clear("encoder_glitch", 3)
        assert emu.active_faults == ["gate_driver on motor 3"]
        with pytest.raises(TypeError, match=r"give the motor once, as `motor=`"):
            emu.inject("gate_driver", 3, motor=3)
        with pytest.raises(TypeError, match=r"give the motor once, as `motor=`"):
            emu.clear("gate_driver", can_id=3, motor=3)
