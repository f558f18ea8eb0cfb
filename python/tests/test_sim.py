"""The emulators as Python objects: lifecycle, fault vocabularies, state inspection."""

import socket

import pytest

import armhil.sim


def test_realman_context_manager_starts_and_stops():
    with armhil.sim.realman() as emu:
        assert emu.running and emu.port > 0
        socket.create_connection((emu.host, emu.port), timeout=2).close()
        port = emu.port
        assert len(emu.joints_deg()) == 6
        assert emu.state()["power_on"] is True
    assert not emu.running
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
    emu.stop()  # idempotent
    with pytest.raises(RuntimeError):
        emu.joints_deg()


def test_realman_initial_joints_and_faults():
    with armhil.sim.realman(initial_joints_deg=[0, 10, 20, 0, 30, 0]) as emu:
        assert abs(emu.joints_deg()[1] - 10) < 0.01
        emu.inject("power_loss")
        assert emu.state()["power_on"] is False
        emu.clear("power_loss")
        assert emu.state()["power_on"] is True
        with pytest.raises(ValueError, match="comm_loss"):
            emu.inject("comm_loss")  # a Piper fault, not a Realman one
        with pytest.raises(ValueError, match="delay_ms"):
            emu.inject("reply_delay")
        with pytest.raises(ValueError, match="dleay_ms"):
            emu.inject("reply_delay", delay_ms=10, dleay_ms=3)


def test_piper_faults_and_state():
    with armhil.sim.piper(initial_joints_deg=[0, 10, -10, 0, 0, 0]) as emu:
        assert emu.port > 0
        assert abs(emu.joints_deg()[1] - 10) < 0.05
        emu.inject("motor_over_temp", joint=2, temp_c=95)
        assert emu.state()["motor_temps_c"][1] == pytest.approx(95, abs=1)
        emu.clear("motor_over_temp", joint=2)
        with pytest.raises(ValueError, match="joint"):
            emu.inject("comm_loss")
        with pytest.raises(ValueError):
            emu.inject("comm_loss", joint=9)
        with pytest.raises(ValueError, match="reply_delay"):
            emu.inject("reply_delay", delay_ms=1)


def test_robstride_faults_show_in_the_fault_word():
    with armhil.sim.robstride(motors=["1:RS03", "2:RS00"]) as emu:
        motors = emu.state()
        assert [m["can_id"] for m in motors] == [1, 2]
        assert all(m["fault_word"] == 0 for m in motors)
        emu.inject("over_temperature", motor=1)
        motors = emu.state()
        assert motors[0]["fault_word"] & 1
        assert motors[1]["fault_word"] == 0
        assert "socketcand" in emu.params
        with pytest.raises(ValueError):
            emu.inject("over_temperature", motor=99)
