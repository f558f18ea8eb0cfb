"""Realman faults from Python go through the emulator's one fault builder: what a scenario file
refuses is refused here too, with the same message."""

import pytest

import armhil.sim


def test_a_refused_fault_value_gives_the_scenario_message():
    with armhil.sim.realman() as emu:
        with pytest.raises(ValueError, match=r"^`delay_ms`: -5 out of range, expected 1\.\.=60000$"):
            emu.inject("reply_delay", delay_ms=-5)
        # `code` used to default to 8 here; scenario files and the web view require it.
        with pytest.raises(ValueError, match=r"^`joint_error` needs `code`$"):
            emu.inject("joint_error", joint=2)
        with pytest.raises(ValueError, match=r"^`count`: expected a whole number, got 1\.5$"):
            emu.inject("malformed_reply", count=1.5)
        with pytest.raises(ValueError, match="no Realman fault `comm_loss`; known: connection_drop"):
            emu.inject("comm_loss")
        with pytest.raises(ValueError, match=r"^`peer_ip`: `nowhere` is not an IP address$"):
            emu.inject("connection_drop", peer_ip="nowhere")
        emu.inject("joint_error", joint=2, code=8)
        emu.clear("joint_error")
