"""The RobStride MIT variant and the host-tool parameter tables against python-can (4.6.1,
unchanged) over socketcand, talking to `armhil sim robstride --socketcand`.

Run (after `cargo build -p armhil`):

    pip install python-can==4.6.1 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_robstride_mit.py

The switch is the real flow: the emulator starts in the private protocol with a state file,
python-can sends type 25 with F_CMD = 2 to motor 5, the emulator is stopped (the motor "loses
power") and started again on the same file. Motor 5 then speaks only 11-bit MIT frames; motors
6 (RS03) and 7 (RS04) stay private and answer the type-17 reads of the 0x20xx/0x30xx tables the
official RobStride Python SDK makes (0x2005, 0x3016, 0x3017, 0x302C), which used to fail.
Frames are built here by hand from the protocol note, as a user of python-can would.
"""

import math
import os
import struct
import time

import pytest

from armhil_process import free_port, listening

if os.environ.get("CI"):
    import can
else:
    can = pytest.importorskip("can")

MIT = 5
CHANNEL = "can0"
HOST = 0xFD
FF6 = [0xFF] * 6
P = 4 * math.pi  # RS03 angle range
V, T, KP, KD = 20.0, 60.0, 5000.0, 100.0  # RS03 speed, torque, Kp, Kd ranges


def emulator_args(port, state_file):
    return [
        "sim", "robstride", "--socketcand", f"127.0.0.1:{port}",
        "--motor", f"{MIT}:RS03", "--motor", "6:RS03", "--motor", "7:RS04",
        "--state-file", str(state_file),
    ]


def receive(bus, predicate, timeout_s=2.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = bus.recv(0.1)
        if msg is not None and predicate(msg):
            return msg
    return None


def drain(bus):
    while bus.recv(0) is not None:
        pass


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """Motor 5 switched to MIT and power-cycled; yields (host, port)."""
    state_file = tmp_path_factory.mktemp("robstride-mit") / "state.json"
    port = free_port()
    with listening(emulator_args(port, state_file), port) as proc:
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel=CHANNEL)
        try:
            bus.send(can.Message(arbitration_id=0x1900_0000 | HOST << 8 | MIT,
                                 is_extended_id=True, data=[1, 2, 3, 4, 5, 6, 2, 0]))
            reply = receive(bus, lambda m: m.is_extended_id and m.arbitration_id >> 24 == 0)
            assert reply is not None, "type-0 confirmation of the protocol switch"
        finally:
            bus.shutdown()
    assert proc.returncode == 0, proc.stderr_tail
    assert '"protocol": 2' in state_file.read_text()
    port = free_port()
    with listening(emulator_args(port, state_file), port) as proc:
        yield ("127.0.0.1", port)
    assert proc.returncode == 0, f"emulator exit {proc.returncode}: {proc.stderr_tail}"


@pytest.fixture()
def bus(server):
    host, port = server
    b = can.Bus(interface="socketcand", host=host, port=port, channel=CHANNEL)
    try:
        yield b
    finally:
        b.shutdown()


def to_uint(x, lo, hi, bits):
    x = min(max(x, lo), hi)
    return int((x - lo) * ((1 << bits) - 1) / (hi - lo))


def from_uint(u, lo, hi, bits):
    return u * (hi - lo) / ((1 << bits) - 1) + lo


def mit_send(bus, data, kind=0):
    bus.send(can.Message(arbitration_id=kind << 8 | MIT, is_extended_id=False, data=data))


def response1(bus):
    """The next Response 1 of motor 5: (mode, fault, angle, speed, torque, temp_c)."""
    msg = receive(bus, lambda m: not m.is_extended_id and m.arbitration_id == HOST
                  and m.data[0] == MIT and any(m.data[5:8]))
    assert msg is not None, "Response 1"
    d = msg.data
    return (
        d[6] >> 6,
        bool(d[6] & 0x20),
        from_uint(d[1] << 8 | d[2], -P, P, 16),
        from_uint(d[3] << 4 | d[4] >> 4, -V, V, 12),
        from_uint((d[4] & 0x0F) << 8 | d[5], -T, T, 12),
        ((d[6] & 0x0F) << 8 | d[7]) / 10.0,
    )


def command(bus, f_cmd, marker):
    drain(bus)
    mit_send(bus, FF6 + [f_cmd, marker])


def setpoint(angle, speed, kp, kd, torque):
    a, v = to_uint(angle, -P, P, 16), to_uint(speed, -V, V, 12)
    p, d, t = to_uint(kp, 0, KP, 12), to_uint(kd, 0, KD, 12), to_uint(torque, -T, T, 12)
    return [a >> 8, a & 0xFF, v >> 4, (v & 0xF) << 4 | p >> 8, p & 0xFF, d >> 4,
            (d & 0xF) << 4 | t >> 8, t & 0xFF]


def mit_read_bytes(bus, index):
    """Command 14: the four value bytes of `index`."""
    drain(bus)
    mit_send(bus, [index & 0xFF, index >> 8, 0, 0, 0, 0, 0, 0], kind=3)
    msg = receive(bus, lambda m: not m.is_extended_id and m.arbitration_id == 3 << 8 | MIT)
    assert msg is not None, f"reply to the read of {index:#06x}"
    assert msg.data[0] | msg.data[1] << 8 == index
    return bytes(msg.data[4:8])


def mit_read(bus, index):
    return struct.unpack("<f", mit_read_bytes(bus, index))[0]


def private_read(bus, motor, index):
    """A type-17 read as the official SDK makes it: (status byte, f32 value)."""
    drain(bus)
    bus.send(can.Message(arbitration_id=0x1100_0000 | HOST << 8 | motor, is_extended_id=True,
                         data=[index & 0xFF, index >> 8, 0, 0, 0, 0, 0, 0]))
    msg = receive(bus, lambda m: m.is_extended_id and m.arbitration_id >> 24 == 17
                  and (m.arbitration_id >> 8) & 0xFF == motor)
    assert msg is not None, f"type-17 reply from motor {motor}"
    return (msg.arbitration_id >> 16) & 0xFF, struct.unpack("<f", bytes(msg.data[4:8]))[0]


def test_private_motors_serve_the_sdk_host_table_reads(bus):
    # RS03: 0x3016 mechPos, 0x3017 mechVel, 0x302C torque_fdb, 0x2005 MechOffset.
    for index in (0x3016, 0x3017, 0x302C, 0x2005):
        status, value = private_read(bus, 6, index)
        assert status == 0, f"{index:#06x} answered the failure flag"
        assert abs(value) < 1e-3, f"{index:#06x} = {value} at rest"
    # Turn motor 6 with a type-1 frame (kp 0, kd 5, speed 2 rad/s) and read mechVel both ways.
    bus.send(can.Message(arbitration_id=0x0300_0000 | HOST << 8 | 6, is_extended_id=True,
                         data=[0] * 8))
    torque = to_uint(0.0, -T, T, 16)
    speed = to_uint(2.0, -V, V, 16)
    kd = to_uint(5.0, 0, KD, 16)
    for _ in range(20):
        bus.send(can.Message(arbitration_id=0x0100_0000 | torque << 8 | 6, is_extended_id=True,
                             data=[0x7F, 0xFF, speed >> 8, speed & 0xFF, 0, 0, kd >> 8, kd & 0xFF]))
        time.sleep(0.05)
    status, vel = private_read(bus, 6, 0x3017)
    assert status == 0 and abs(vel - 2.0) < 0.1, vel
    _, vel_70xx = private_read(bus, 6, 0x701B)
    assert abs(vel - vel_70xx) < 0.1
    # RS04 is shifted by one: mechPos at 0x3017, mechVel at 0x3018.
    assert private_read(bus, 7, 0x3017)[0] == 0
    assert private_read(bus, 7, 0x3018)[0] == 0
    # Strings still fail, as on hardware.
    assert private_read(bus, 6, 0x1003)[0] == 1
    bus.send(can.Message(arbitration_id=0x0400_0000 | HOST << 8 | 6, is_extended_id=True,
                         data=[0] * 8))


def test_private_frames_go_unanswered_after_the_switch(bus):
    drain(bus)
    bus.send(can.Message(arbitration_id=0x0000_0000 | HOST << 8 | MIT, is_extended_id=True,
                         data=[0] * 8))
    assert receive(bus, lambda m: m.is_extended_id and (m.arbitration_id >> 8) & 0xFF == MIT,
                   timeout_s=0.5) is None


def test_mit_mode_position_mode_velocity_mode_and_faults(bus):
    # MIT mode: enable, then setpoints toward 0.5 rad (kp 50, kd 2; a disc, no gravity).
    command(bus, 0xFF, 0xFC)
    mode, fault, *_ = response1(bus)
    assert (mode, fault) == (2, False)
    for _ in range(30):
        mit_send(bus, setpoint(0.5, 0.0, 50.0, 2.0, 0.0))
        time.sleep(0.03)
    drain(bus)
    mit_send(bus, setpoint(0.5, 0.0, 50.0, 2.0, 0.0))
    _, _, angle, speed, _, temp = response1(bus)
    assert abs(angle - 0.5) < 0.02 and abs(speed) < 0.1, (angle, speed)
    assert 20.0 < temp < 40.0
    # Position mode (CSP): stop, mode 1, enable, command 10 (f32 angle, f32 speed limit).
    command(bus, 0xFF, 0xFD)
    response1(bus)
    command(bus, 0x01, 0xFC)
    response1(bus)
    assert mit_read_bytes(bus, 0x7005)[0] == 5  # run_mode (u8): position mode is CSP
    command(bus, 0xFF, 0xFC)
    response1(bus)
    drain(bus)
    mit_send(bus, list(struct.pack("<ff", -1.0, 3.0)), kind=1)
    response1(bus)
    time.sleep(1.5)
    assert abs(mit_read(bus, 0x7019) - -1.0) < 0.02
    assert abs(mit_read(bus, 0x3016) - -1.0) < 0.02  # the host table, in MIT too
    # Velocity mode: stop, mode 2, enable, command 11 (f32 speed, f32 current limit).
    command(bus, 0xFF, 0xFD)
    response1(bus)
    command(bus, 0x02, 0xFC)
    response1(bus)
    command(bus, 0xFF, 0xFC)
    response1(bus)
    drain(bus)
    mit_send(bus, list(struct.pack("<ff", 3.0, 10.0)), kind=2)
    response1(bus)
    time.sleep(1.0)
    assert abs(mit_read(bus, 0x701B) - 3.0) < 0.1
    command(bus, 0xFF, 0xFD)
    mode, *_ = response1(bus)
    assert mode == 0
    # Fault query (command 5, F_CMD 0): motor ID and a clean fault word, bytes 5..7 zero.
    command(bus, 0x00, 0xFB)
    msg = receive(bus, lambda m: not m.is_extended_id and m.arbitration_id == HOST
                  and m.data[0] == MIT)
    assert msg is not None and list(msg.data) == [MIT, 0, 0, 0, 0, 0, 0, 0]


def test_command_8_answers_with_the_uid_from_the_motor_id(bus):
    command(bus, 0x00, 0xFD)
    msg = receive(bus, lambda m: not m.is_extended_id and m.arbitration_id == MIT)
    assert msg is not None and len(msg.data) == 8, "Response 2 with the MCU UID"
    # Still MIT until the next power-on: an enable is answered with Response 1.
    command(bus, 0xFF, 0xFC)
    assert response1(bus)[0] == 2
    command(bus, 0xFF, 0xFD)
    response1(bus)
