"""Smoke check for the python hook environment: python-can is importable in the VM and two
SocketCAN sockets on the vcan interface see each other's standard and extended frames.

Runs first (name order) so that a broken interpreter or interface shows up here, with a clear
message, rather than inside the vendor-SDK hooks that follow.
"""

import os
import sys

import can

IFACE = os.environ.get("ARMHIL_VCAN_IFACE", "vcan0")
TIMEOUT_S = 10.0


def main() -> int:
    sent = [
        can.Message(arbitration_id=0x2A1, data=bytes([1, 2, 3]), is_extended_id=False),
        can.Message(arbitration_id=0x0200FD01, data=bytes(range(8)), is_extended_id=True),
    ]
    with can.Bus(interface="socketcan", channel=IFACE) as tx, can.Bus(
        interface="socketcan", channel=IFACE
    ) as rx:
        for msg in sent:
            tx.send(msg)
        for want in sent:
            got = rx.recv(timeout=TIMEOUT_S)
            if got is None:
                print(f"no frame within {TIMEOUT_S}s on {IFACE}", file=sys.stderr)
                return 1
            if (got.arbitration_id, got.is_extended_id, bytes(got.data)) != (
                want.arbitration_id,
                want.is_extended_id,
                bytes(want.data),
            ):
                print(f"expected {want}, got {got}", file=sys.stderr)
                return 1
    print(f"python {sys.version.split()[0]}, python-can {can.__version__}: frames round-trip on {IFACE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
