"""The generated C++ subscriber accepts values only from the SubBroker (the
issue: one idle socket held back every value for 20 s, and a value written by
anyone was printed as real). The subscriber serves several connections at
once, drops one that does not prove the delivery key in time, and refuses a
connection whose first line is not that proof. The SubBroker's side is its
real TCP delivery (modd.subbroker.delivery), the proof checked against
Python's hmac. Two SubBrokers (two stations) delivering the same windows: each
is printed once (docs/fleet.md)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest
from modd.ports import free_port
from modd.subbroker import delivery_auth
from modd.subbroker.delivery import TcpDelivery
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix
from modd_gen import generate, write_artifacts
from modd_model import load_model

KEY = "0123456789abcdef-test-delivery-key"


class Output:
    """The subscriber's stdout, read on a thread."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.lines: list[str] = []
        assert proc.stdout is not None
        self._stream = proc.stdout
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._thread.join(timeout=10)
        self._stream.close()

    def _read(self) -> None:
        for line in self._stream:
            self.lines.append(line.rstrip("\n"))

    def wait(self, text: str, timeout: float) -> float:
        start = time.monotonic()
        while time.monotonic() - start < timeout:
            if any(text in line for line in self.lines):
                return time.monotonic() - start
            time.sleep(0.01)
        raise AssertionError(f"{text!r} not printed within {timeout} s: {self.lines}")


@pytest.fixture(scope="module")
def exe(scenarios_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("sub")
    write_artifacts(out, generate(load_model(scenarios_dir / "scenario1.modd"), "scientist"))
    project = out / "scientist" / "cpp" / "sub_5"
    for cmd in (
        ["cmake", "-S", str(project), "-B", str(project / "build"), "-G", "Ninja"],
        ["cmake", "--build", str(project / "build")],
    ):
        subprocess.run(cmd, check=True, capture_output=True, timeout=600)
    return project / "build" / "sub_5_subscriber"


@pytest.fixture
def subscriber(
    exe: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Iterator[tuple[int, Output]]:
    key_file = tmp_path / "delivery.key"
    key_file.write_text(KEY + "\n")
    key_file.chmod(0o600)
    monkeypatch.setenv("MODD_DELIVERY_KEY", f"file:{key_file}")  # this process's SubBroker side
    port = free_port()
    proc = subprocess.Popen(
        [str(exe)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "MODD_SUBSCRIBER_PORT": str(port)},
    )
    out = Output(proc)
    try:
        out.wait("listening on", 10)
        yield port, out
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=10)
        out.close()
    assert proc.returncode == 0, out.lines


def _value(end_ns: int, value: float) -> DeliveredValue:
    return DeliveredValue(
        subscriber="sub_5",
        topic="usv.accelerometer.accel_z",
        aggregation="MIN",
        period_s="0.25",
        unit="METER_PER_SECOND_SQUARED",
        config_id=1,
        slot=end_ns,
        start_ns=end_ns - 1,
        end_ns=end_ns,
        value=value,
        count=None,
        delivered_ns=end_ns,
    )


def _line(v: DeliveredValue) -> bytes:
    return json.dumps(v.to_dict()).encode() + b"\n"


def _greeting(sock: socket.socket) -> str:
    sock.settimeout(5)
    data = b""
    while not data.endswith(b"\n"):
        chunk = sock.recv(256)
        assert chunk, "closed before the challenge"
        data += chunk
    assert data.startswith(delivery_auth.GREETING)
    return data[len(delivery_auth.GREETING) : -1].decode()


def test_idle_sockets_do_not_hold_back_values(subscriber: tuple[int, Output]) -> None:
    port, out = subscriber
    idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(20)]
    try:
        for s in idle[-3:]:
            _greeting(s)  # connected and challenged, then silent
        tcp = TcpDelivery({"sub_5": ("127.0.0.1", port)}, queue_size=10)
        try:
            tcp.deliver(_value(1_000_000_001, 0.5))
            took = out.wait("1000000001 usv.accelerometer.accel_z MIN = 0.5", 5)
        finally:
            tcp.close()
        assert took < 2.0  # the SubBroker's 0.5 s wait for a challenge, not the idle sockets
        # An unproven connection is dropped after the handshake timeout (5 s).
        idle[-1].settimeout(8)
        assert idle[-1].recv(1) == b""
    finally:
        for s in idle:
            s.close()


@pytest.mark.parametrize(
    "answer",
    [
        b"",  # no proof at all: the forged value is the first line
        b"AUTH " + b"0" * 64 + b"\n",  # a wrong proof
        b"AUTH " + delivery_auth.proof(b"another key", "00").encode() + b"\n",
    ],
)
def test_forged_values_are_refused(subscriber: tuple[int, Output], answer: bytes) -> None:
    port, out = subscriber
    with socket.create_connection(("127.0.0.1", port)) as forger:
        _greeting(forger)
        forger.sendall(answer + _line(_value(2_000_000_002, 1e9)))
        forger.settimeout(5)
        assert forger.recv(1) == b""  # the subscriber hung up on it
    # The genuine SubBroker is still heard, and the forged value never was.
    tcp = TcpDelivery({"sub_5": ("127.0.0.1", port)}, queue_size=10)
    try:
        tcp.deliver(_value(3_000_000_003, 0.25))
        out.wait("3000000003 usv.accelerometer.accel_z MIN = 0.25", 5)
    finally:
        tcp.close()
    assert not any("2000000002" in line for line in out.lines), out.lines


def test_a_proof_from_the_key_is_accepted(subscriber: tuple[int, Output]) -> None:
    """The proof computed with Python's hmac (an independent implementation of
    the C++ client's SHA-256) opens the connection."""
    port, out = subscriber
    with socket.create_connection(("127.0.0.1", port)) as peer:
        nonce = _greeting(peer)
        peer.sendall(
            b"AUTH "
            + delivery_auth.proof(KEY.encode(), nonce).encode()
            + b"\n"
            + _line(_value(4_000_000_004, -0.75))
        )
        out.wait("4000000004 usv.accelerometer.accel_z MIN = -0.75", 5)
        # Proven, the connection outlives the 5 s handshake timeout (the idle one is 300 s).
        time.sleep(5.5)
        peer.sendall(_line(_value(4_000_000_005, 0.125)))
        out.wait("4000000005 usv.accelerometer.accel_z MIN = 0.125", 5)


def test_out_of_range_integers_are_malformed_not_undefined(subscriber: tuple[int, Output]) -> None:
    port, out = subscriber
    with socket.create_connection(("127.0.0.1", port)) as peer:
        nonce = _greeting(peer)
        bad = json.loads(_line(_value(5_000_000_005, 1.0)))
        bad["end_ns"] = 1e300
        peer.sendall(
            b"AUTH "
            + delivery_auth.proof(KEY.encode(), nonce).encode()
            + b"\n"
            + json.dumps(bad).encode()
            + b"\n"
            + _line(_value(6_000_000_006, 2.0))
        )
        out.wait("6000000006 usv.accelerometer.accel_z MIN = 2", 5)
    assert not any(line.startswith("-9223372036854775808") for line in out.lines)


EPOCH, OTHER_EPOCH, Q = 1_700_000_000_000_000_000, 1_700_000_060_000_000_000, 250_000_000


def _window(k: int, epoch: int = EPOCH, identity: bool = True) -> tuple[bytes, int]:
    """Window ``k`` of sub_5 as the SubBroker's fast path writes it, and its end."""
    head = StreamPayload(
        "usv.accelerometer.accel_z", "MIN", "0.25", "METER_PER_SECOND_SQUARED", 1,
        ("usv", epoch, Q) if identity else None,
    )  # fmt: skip
    start = epoch + k * Q
    line = head.tail(abs(k), start, start + Q, 0.5, None, start + Q)  # slot: the index
    return subscriber_prefix("sub_5") + line, start + Q


def test_two_stations_windows_are_printed_once(subscriber: tuple[int, Output]) -> None:
    """Both stations deliver windows 0-2, window 0 of another epoch and a value
    without identity (an older SubBroker), then a window of their own: the windows
    are printed once, the value without identity twice (both stations were heard)."""
    port, out = subscriber
    windows = [_window(k) for k in range(3)] + [_window(0, OTHER_EPOCH)]
    old = _window(-4000, identity=False)
    stations = [TcpDelivery({"sub_5": ("127.0.0.1", port)}, queue_size=100) for _ in range(2)]
    marks = [_window(10), _window(11)]
    try:
        for tcp, mark in zip(stations, marks, strict=True):
            for line, _ in [*windows, old, mark]:
                tcp.put("sub_5", line)
        for _, end in marks:  # each station's last: its other lines came before
            out.wait(f"{end} usv.accelerometer.accel_z MIN", 10)
    finally:
        for tcp in stations:
            tcp.close()
    printed = Counter(line.split()[0] for line in out.lines if " MIN = " in line)
    assert printed == Counter({str(end): 1 for _, end in windows + marks} | {str(old[1]): 2})
