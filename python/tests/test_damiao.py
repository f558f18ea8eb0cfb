"""Damiao (DM) motors under Python control (``armhil.sim.damiao``): the emulator behind a
socketcand server, reached by python-can as a Damiao client would be, its state, and its
faults through the emulator's one fault builder (``inject(name, **kwargs)`` with the fault
table's names: ``motor=`` the ESC_ID, and the fault's own values)."""

import os
import struct
import time

import pytest

if os.environ.get("CI"):
    # In CI scripts/ci/python.sh installs it: a missing client is a failure, not a skip.
    import can
else:
    can = pytest.importorskip("can")

import armhil.sim  # noqa: E402

ENABLE = b"\xff" * 7 + b"\xfc"
CLEAR = b"\xff" * 7 + b"\xfb"
REGISTERS = 0x7FF
READ, REFRESH = 0x33, 0xCC
RID_VMAX = 22


def open_bus(emu):
    return can.Bus(interface="socketcand", host=emu.host, port=emu.port, channel="can0")


def send(bus, arbitration_id, data):
    bus.send(can.Message(arbitration_id=arbitration_id, is_extended_id=False, data=data))


def reply_on(bus, arbitration_id, timeout_s=2.0):
    """The first frame on `arbitration_id` within `timeout_s`, or None."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = bus.recv(timeout=0.05)
        if msg is not None and msg.arbitration_id == arbitration_id:
            return msg
    return None


def refresh(bus, esc_id, mst_id):
    """The motor's state nibble, from the feedback frame answering a refresh."""
    send(bus, REGISTERS, [esc_id, 0, REFRESH, 0, 0, 0, 0, 0])
    msg = reply_on(bus, mst_id)
    assert msg is not None, f"no feedback on 0x{mst_id:03X}"
    assert msg.data[0] & 0x0F == esc_id & 0x0F
    return msg.data[0] >> 4


def test_damiao_context_manager_state_and_params():
    with armhil.sim.damiao(motors=["1:DM4310", "0x04:DM4340:0x24"]) as emu:
        assert emu.running and emu.port > 0 and emu.host == "127.0.0.1"
        assert emu.params["socketcand"] == f"127.0.0.1:{emu.port}"
        motors = emu.state()
        assert [(m["can_id"], m["mst_id"], m["model"]) for m in motors] == [
            (1, 0x11, "DM4310"),
            (4, 0x24, "DM4340"),
        ]
        for m in motors:
            assert m["enabled"] is False and m["state"] == 0 and m["faults"] == []
            assert m["ctrl_mode"] == 1 and m["mode"] == "mit"
            assert m["bus_voltage_v"] == pytest.approx(24.0)
        names = [f["name"] for f in emu.faults()]
        assert names == [
            "over_voltage", "under_voltage", "over_current", "mos_over_temperature",
            "coil_over_temperature", "comm_lost", "overload",
        ]
    assert not emu.running
    emu.stop()  # idempotent
    with pytest.raises(RuntimeError, match="the Damiao emulator is stopped"):
        emu.state()
    with pytest.raises(RuntimeError, match="the Damiao emulator is stopped"):
        emu.inject("overload", motor=1)


def test_a_python_can_client_enables_a_motor_and_reads_a_register():
    with armhil.sim.damiao(motors=["1:DM4310", "4:DM4340"]) as emu:
        bus = open_bus(emu)
        try:
            send(bus, 1, ENABLE)
            feedback = reply_on(bus, 0x11)
            assert feedback is not None and feedback.data[0] == 0x11, feedback
            assert [m["enabled"] for m in emu.state()] == [True, False]

            send(bus, REGISTERS, [4, 0, READ, RID_VMAX, 0, 0, 0, 0])
            reply = reply_on(bus, 0x14)
            assert reply is not None and bytes(reply.data[:4]) == bytes([4, 0, READ, RID_VMAX])
            assert struct.unpack("<f", bytes(reply.data[4:]))[0] == 10.0  # DM4340
        finally:
            bus.shutdown()


def test_a_fault_latches_until_the_host_clears_it():
    with armhil.sim.damiao(motors=["1:DM4310", "2:DM4310"]) as emu:
        bus = open_bus(emu)
        try:
            emu.inject("over_voltage", motor=1, voltage_v=40)
            assert emu.active_faults == ["over_voltage voltage_v=40 on motor 1"]
            motors = emu.state()
            assert motors[0]["faults"] == ["over_voltage"] and motors[0]["state"] == 0x8
            assert motors[0]["bus_voltage_v"] == pytest.approx(40.0)
            assert motors[1]["faults"] == [] and motors[1]["state"] == 0
            assert refresh(bus, 1, 0x11) == 0x8

            # The cause goes; the latch stays until the host's clear (FF…FB).
            emu.clear("over_voltage", motor=1)
            assert emu.active_faults == []
            assert emu.state()[0]["faults"] == ["over_voltage"]
            assert refresh(bus, 1, 0x11) == 0x8
            send(bus, 1, CLEAR)
            cleared = reply_on(bus, 0x11)
            assert cleared is not None and cleared.data[0] >> 4 == 0
            assert emu.state()[0]["faults"] == [] and emu.state()[0]["state"] == 0

            # Communication lost, as the CAN timeout would latch it.
            emu.inject("comm_lost", motor=2)
            assert emu.state()[1]["faults"] == ["comm_lost"]
            assert refresh(bus, 2, 0x12) == 0xD
        finally:
            bus.shutdown()


def test_bad_fault_arguments_are_refused_with_the_builder_s_message():
    with armhil.sim.damiao(motors=["1:DM4310"]) as emu:
        with pytest.raises(ValueError, match=r"^no Damiao fault `melted`; known: over_voltage, "):
            emu.inject("melted", motor=1)
        with pytest.raises(ValueError, match=r"`overload` needs `motor`"):
            emu.inject("overload")
        with pytest.raises(ValueError, match=r"has no argument `volts`"):
            emu.inject("over_voltage", motor=1, volts=40)
        with pytest.raises(ValueError, match=r"`voltage_v`"):
            emu.inject("over_voltage", motor=1, voltage_v=5)  # below OV_Value
        with pytest.raises(ValueError, match=r"ESC_ID 0x007"):
            emu.inject("overload", motor=7)  # no motor there
        assert emu.active_faults == [] and emu.state()[0]["faults"] == []


def test_inject_is_documented_with_every_fault_and_refuses_a_wrong_keyword_by_name():
    with armhil.sim.damiao() as emu:
        names = [f["name"] for f in emu.faults()]
        doc = type(emu).inject.__doc__
        assert [n for n in names if n not in doc] == []
        for name in names:
            with pytest.raises(ValueError, match=rf"^fault `{name}` has no argument `no_such_arg`"):
                emu.inject(name, motor=1, no_such_arg=1)
            with pytest.raises(ValueError, match=rf"^fault `{name}` has no argument `no_such_arg`"):
                emu.clear(name, motor=1, no_such_arg=1)
        assert emu.active_faults == []


@pytest.mark.parametrize(
    "motors, message",
    [
        (["1"], r"expected ID:MODEL or ID:MODEL:FEEDBACK_ID"),
        (["1:DM9999"], r"unknown Damiao model"),
        (["0:DM4310"], r"ESC_ID \"0\": expected a number in 1\.\.=1278"),
        (["1:DM4310:0x800"], r"feedback id \"0x800\""),
        (["1:DM4310:0x7FF"], r"0x7FF is the register identifier"),
        (["1:DM4310:0x102", "2:DM4310"], r"a command identifier of the motor on ESC_ID 2"),
        (["1:DM4310", "1:DM4340:0x21"], r"two motors use ESC_ID 0x001"),
    ],
)
def test_bad_motor_strings_are_refused(motors, message):
    with pytest.raises(ValueError, match=message):
        armhil.sim.damiao(motors=motors)
