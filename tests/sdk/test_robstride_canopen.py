"""The RobStride CANopen variant against an unchanged CiA-301 master: the `canopen` package
(PyPI, 2.4.1; its RemoteNode / BaseNode402 unpatched) and python-can over socketcand, talking to
`armhil sim robstride --socketcand`.

Run (after `cargo build -p armhil`):

    pip install python-can==4.6.1 canopen==2.4.1 pytest
    ARMHIL_BIN=target/debug/armhil python -m pytest -v tests/sdk/test_robstride_canopen.py

How a motor comes up speaking CANopen is the real flow: the emulator starts in the private
protocol with a state file, python-can sends type 25 with F_CMD = 1, the emulator is stopped
(the motor "loses power") and started again on the same state file. From then on everything
goes through the `canopen` package: NMT, heartbeat, SDO, the CiA-402 state machine, EMCY.

The object dictionary is built here from the objects the drive documents (the vendor's EDS
describes PDOs this emulator does not serve; the node is SDO-only). Mode numbers are the
drive's own (5 = cyclic synchronous position), written as plain SDO values: BaseNode402's
`op_mode` speaks DS402 numbering (CSP = 8) and would select the wrong mode on this drive.
"""

import os
import time

import pytest

from armhil_process import free_port, listening

if os.environ.get("CI"):
    import can
    import canopen
else:
    can = pytest.importorskip("can")
    canopen = pytest.importorskip("canopen")

from canopen.objectdictionary import ODRecord, ODVariable, ObjectDictionary  # noqa: E402
from canopen.objectdictionary import datatypes as dt  # noqa: E402
from canopen.sdo import SdoAbortedError  # noqa: E402

NODE = 5
CHANNEL = "can0"


def variable(index, sub, name, data_type, access):
    var = ODVariable(name, index, sub)
    var.data_type = data_type
    var.access_type = access
    return var


def object_dictionary():
    """The drive's documented objects, with the types of the vendor's EDS."""
    od = ObjectDictionary()
    plain = [
        (0x1000, "Device type", dt.UNSIGNED32, "ro"),
        (0x1001, "Error register", dt.UNSIGNED8, "ro"),
        (0x1017, "Producer heartbeat time", dt.UNSIGNED16, "rw"),
        (0x603F, "Error code", dt.UNSIGNED16, "ro"),
        (0x6040, "Controlword", dt.UNSIGNED16, "rw"),
        (0x6041, "Statusword", dt.UNSIGNED16, "ro"),
        (0x6060, "Modes of operation", dt.INTEGER8, "rw"),
        (0x6061, "Modes of operation display", dt.INTEGER8, "ro"),
        (0x6064, "Position actual value", dt.INTEGER32, "ro"),
        (0x606C, "Velocity actual value", dt.INTEGER32, "ro"),
        (0x6071, "Target torque", dt.INTEGER16, "rw"),
        (0x6077, "Torque actual value", dt.INTEGER16, "ro"),
        (0x6078, "Current actual value", dt.INTEGER16, "ro"),
        (0x6079, "DC link circuit voltage", dt.UNSIGNED32, "ro"),
        (0x607A, "Target position", dt.INTEGER32, "rw"),
        (0x6081, "Profile velocity", dt.UNSIGNED32, "rw"),
        (0x6083, "Profile acceleration", dt.UNSIGNED32, "rw"),
        (0x60FF, "Target velocity", dt.INTEGER32, "rw"),
        # Not served by the drive: here so the tests can see the abort.
        (0x6502, "Supported drive modes", dt.UNSIGNED32, "ro"),
    ]
    for index, name, data_type, access in plain:
        od.add_object(variable(index, 0, name, data_type, access))
    identity = ODRecord("Identity", 0x1018)
    for sub, name, data_type in [
        (0, "Highest sub-index", dt.UNSIGNED8),
        (1, "Vendor-ID", dt.UNSIGNED32),
        (2, "Product code", dt.UNSIGNED32),
        (3, "Revision number", dt.UNSIGNED32),
        (4, "Serial number", dt.UNSIGNED32),
    ]:
        identity.add_member(variable(0x1018, sub, name, data_type, "ro"))
    od.add_object(identity)
    watchdog = ODRecord("Watchdog", 0x6099)
    watchdog.add_member(variable(0x6099, 0, "Highest sub-index", dt.UNSIGNED8, "ro"))
    watchdog.add_member(variable(0x6099, 1, "CAN timeout", dt.UNSIGNED32, "rw"))
    od.add_object(watchdog)
    return od


def emulator_args(port, state_file):
    return [
        "sim", "robstride", "--socketcand", f"127.0.0.1:{port}",
        "--motor", f"{NODE}:RS03", "--state-file", str(state_file),
    ]


@pytest.fixture(scope="module")
def canopen_server(tmp_path_factory):
    """An RS03 switched to CANopen and power-cycled; yields (host, port, state file)."""
    state_file = tmp_path_factory.mktemp("robstride-canopen") / "state.json"
    port = free_port()
    with listening(emulator_args(port, state_file), port) as proc:
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel=CHANNEL)
        try:
            # Type 25, host 0xFD, motor 5: protocol 1 (CANopen) at the next power-on.
            bus.send(can.Message(arbitration_id=0x1900_FD05, is_extended_id=True,
                                 data=[1, 2, 3, 4, 5, 6, 1, 0]))
            reply = receive(bus, lambda m: m.is_extended_id and m.arbitration_id >> 24 == 0)
            assert reply is not None, "type-0 confirmation of the protocol switch"
        finally:
            bus.shutdown()
    assert proc.returncode == 0, proc.stderr_tail
    assert '"protocol": 1' in state_file.read_text()
    port = free_port()
    with listening(emulator_args(port, state_file), port) as proc:
        yield ("127.0.0.1", port, state_file)
    assert proc.returncode == 0, f"emulator exit {proc.returncode}: {proc.stderr_tail}"


def receive(bus, predicate, timeout_s=3.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = bus.recv(0.2)
        if msg is not None and predicate(msg):
            return msg
    return None


@pytest.fixture()
def node(canopen_server):
    """A BaseNode402 on a fresh network connection, after an NMT reset and its boot-up."""
    host, port, _ = canopen_server
    network = canopen.Network()
    network.connect(interface="socketcand", host=host, port=port, channel=CHANNEL)
    drive = canopen.BaseNode402(NODE, object_dictionary())
    network.add_node(drive)
    try:
        drive.nmt.state = "RESET"
        drive.nmt.wait_for_bootup(5)
        assert drive.nmt.state == "PRE-OPERATIONAL"
        drive.setup_402_state_machine(read_pdos=False)
        yield drive
    finally:
        try:
            drive.sdo[0x6040].raw = 0
        finally:
            network.disconnect()


def test_boot_up_nmt_and_heartbeat(node):
    node.sdo[0x1017].raw = 50
    node.nmt.wait_for_heartbeat(2)
    assert node.nmt.state == "PRE-OPERATIONAL"
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.2)
    node.nmt.wait_for_heartbeat(2)
    assert node.nmt.state == "OPERATIONAL"
    node.nmt.state = "STOPPED"
    time.sleep(0.2)
    node.nmt.wait_for_heartbeat(2)
    assert node.nmt.state == "STOPPED"
    node.nmt.state = "PRE-OPERATIONAL"
    time.sleep(0.2)
    node.nmt.wait_for_heartbeat(2)
    assert node.nmt.state == "PRE-OPERATIONAL"
    node.sdo[0x1017].raw = 0


def test_identity_units_and_aborts(node):
    assert node.sdo[0x1000].raw == 0x0002_0192
    assert node.sdo[0x1018][1].raw == 0x556
    assert node.sdo[0x1018][2].raw == 0x4644
    assert node.sdo[0x6079].raw == 48_000  # mV
    assert node.sdo[0x6099][0].raw == 1
    with pytest.raises(SdoAbortedError) as unknown:
        node.sdo.upload(0x2000, 0)
    assert unknown.value.code == 0x0602_0000
    with pytest.raises(SdoAbortedError) as supported_modes:
        node.sdo[0x6502].raw
    assert supported_modes.value.code == 0x0602_0000
    with pytest.raises(SdoAbortedError) as subindex:
        node.sdo.upload(0x6041, 1)
    assert subindex.value.code == 0x0609_0011
    with pytest.raises(SdoAbortedError) as read_only:
        node.sdo.download(0x6064, 0, (0).to_bytes(4, "little"))
    assert read_only.value.code == 0x0601_0002
    with pytest.raises(SdoAbortedError) as mode:
        node.sdo[0x6060].raw = 8  # DS402's CSP number is not this drive's
    assert mode.value.code == 0x0609_0030


def test_cia402_enable_and_csp_motion(node):
    node.sdo[0x6060].raw = 5
    assert node.sdo[0x6061].raw == 5
    assert node.state == "SWITCH ON DISABLED"
    node.state = "OPERATION ENABLED"  # the library walks 6 → 7 → 15
    assert node.state == "OPERATION ENABLED"
    start = node.sdo[0x6064].raw
    target = start + 4096  # a quarter turn
    node.sdo[0x607A].raw = target
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        if abs(node.sdo[0x6064].raw - target) <= 45 and node.statusword & 0x0400:
            break
        time.sleep(0.05)
    assert abs(node.sdo[0x6064].raw - target) <= 45
    assert node.statusword & 0x0400, "target reached"
    node.state = "SWITCH ON DISABLED"
    assert node.state == "SWITCH ON DISABLED"


def test_velocity_mode_and_quick_stop(node):
    node.sdo[0x6060].raw = 3
    node.sdo[0x60FF].raw = 300  # 30 rpm
    node.state = "OPERATION ENABLED"
    time.sleep(1.0)
    assert abs(node.sdo[0x606C].raw - 300) <= 10
    node.state = "QUICK STOP ACTIVE"
    time.sleep(0.5)
    assert node.state == "QUICK STOP ACTIVE"
    assert abs(node.sdo[0x606C].raw) <= 5
    node.state = "SWITCH ON DISABLED"
    node.sdo[0x60FF].raw = 0


def test_watchdog_expiry_faults_with_emcy_and_resets(node):
    node.sdo[0x6060].raw = 5
    node.sdo[0x6099][1].raw = 2000  # 0.1 s
    node.state = "OPERATION ENABLED"
    node.emcy.reset()
    emcy = node.emcy.wait(0x8130, timeout=2)  # silence on the bus for > 0.1 s
    assert emcy is not None, "EMCY on watchdog expiry"
    assert emcy.register & 0x10, "communication error bit"
    assert node.state == "FAULT"
    assert node.sdo[0x603F].raw == 0x8130
    node.sdo[0x6099][1].raw = 0
    node.state = "SWITCH ON DISABLED"  # bit 7 rising: fault reset
    assert node.state == "SWITCH ON DISABLED"
    assert node.sdo[0x603F].raw == 0


def test_fff_frame_switches_back_after_power_cycle(canopen_server, node):
    host, port, state_file = canopen_server
    replies = []
    node.network.subscribe(NODE, lambda can_id, data, ts: replies.append(bytes(data)))
    node.network.send_message(0xFFF, bytes([1, 2, 3, 4, 5, 6, 0]))  # 29-bit: id > 0x7FF
    deadline = time.monotonic() + 2
    while not replies and time.monotonic() < deadline:
        time.sleep(0.02)
    assert len(replies) == 1 and len(replies[0]) == 8, "UID on the standard ID = motor ID"
    # The state file keys each motor by its UID in hex.
    assert f'"{replies[0].hex()}"' in state_file.read_text()
    deadline = time.monotonic() + 2
    while '"protocol": 0' not in state_file.read_text() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert '"protocol": 0' in state_file.read_text()
    # Still CANopen until the power cycle.
    assert node.state == "SWITCH ON DISABLED"
