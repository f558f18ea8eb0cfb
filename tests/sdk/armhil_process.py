"""The `armhil` binary for the vendor-SDK tests: where it is, and emulators started on a free
local port and stopped with Ctrl-C (SIGINT) as a user would."""

import contextlib
import os
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BIN = os.environ.get("ARMHIL_BIN", str(REPO / "target" / "debug" / "armhil"))


def require_binary():
    """Fail (not skip) when the binary is missing: the tests exist to run it."""
    if not Path(BIN).exists():
        pytest.fail(f"armhil binary not found at {BIN} (set ARMHIL_BIN or cargo build -p armhil)")


def free_port(kind=socket.SOCK_STREAM):
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def accepts(port):
    """Whether a server accepts TCP connections on 127.0.0.1:PORT. A connection whose two
    ends are one address is not one: connecting again and again to a free port of the
    ephemeral range can end in a TCP self-connect, which holds the port the server is about
    to bind."""
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=0.2) as s:
            return s.getsockname() != s.getpeername()
    except OSError:
        return False


@contextlib.contextmanager
def listening(args, port, start_timeout_s=20):
    """Run `armhil ARGS` until it accepts TCP connections on 127.0.0.1:PORT; yields the
    process, then stops it with SIGINT. The caller checks `returncode` and `stderr_tail`."""
    require_binary()
    proc = subprocess.Popen(
        [BIN, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + start_timeout_s
    while not accepts(port):
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"emulator did not start: {proc.stderr.read()}")
        time.sleep(0.05)
    try:
        yield proc
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            _, stderr = proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, stderr = proc.communicate()
        proc.stderr_tail = (stderr or "")[-2000:]
