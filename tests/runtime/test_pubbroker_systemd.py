"""The real modd-pubbroker under systemd's notify protocol, with this test as systemd:
a unix datagram socket named by $NOTIFY_SOCKET. READY=1 comes once the link and ingress
listeners accept (the archive is open), WATCHDOG=1 at half of $WATCHDOG_USEC while the
loop runs, none while it is stopped (SIGSTOP: what a hung loop looks like to systemd),
STOPPING=1 at SIGTERM."""

from __future__ import annotations

import signal
import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pubbroker_harness import PubBroker


@pytest.fixture
def notify_socket(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[socket.socket]:
    path = tmp_path / "notify"
    s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    s.bind(str(path))
    monkeypatch.setenv("NOTIFY_SOCKET", str(path))
    monkeypatch.setenv("WATCHDOG_USEC", "400000")  # fed every 0.2 s
    monkeypatch.delenv("WATCHDOG_PID", raising=False)
    yield s
    s.close()


def received(s: socket.socket, seconds: float) -> list[tuple[float, str]]:
    """Every datagram within `seconds`, with its arrival time."""
    out: list[tuple[float, str]] = []
    end = time.monotonic() + seconds
    while (left := end - time.monotonic()) > 0:
        s.settimeout(left)
        try:
            out.append((time.monotonic(), s.recv(256).decode()))
        except TimeoutError:
            break
    return out


def test_ready_then_watchdog_at_half_the_period(tmp_path: Path, notify_socket: Any) -> None:
    b = PubBroker(tmp_path, [("usv.a", "float32")])
    b.start()  # returns once the link port accepts and the ingress socket exists
    try:
        got = received(notify_socket, 2.0)
        states = [m for _, m in got]
        assert states[0].startswith("READY=1\nSTATUS=archiving to "), states[:3]
        assert b.archive_dir.is_dir()  # the archive set up (crashed files recovered) first
        dog = [t for t, m in got if m == "WATCHDOG=1"]
        assert 7 <= len(dog) <= 12, states  # 2 s / 0.2 s
        gaps = [b - a for a, b in zip(dog, dog[1:], strict=False)]
        assert max(gaps) < 0.4  # never as late as WATCHDOG_USEC
        assert b.proc is not None
        b.proc.send_signal(signal.SIGSTOP)  # a loop that no longer runs feeds nothing
        assert received(notify_socket, 1.0) == []
        b.proc.send_signal(signal.SIGCONT)
        assert "WATCHDOG=1" in [m for _, m in received(notify_socket, 0.5)]
    finally:
        assert b.stop() == 0
    assert "STOPPING=1" in [m for _, m in received(notify_socket, 0.5)]


def test_without_notify_socket_nothing_changes(tmp_path: Path, monkeypatch: Any) -> None:
    monkeypatch.delenv("NOTIFY_SOCKET", raising=False)
    b = PubBroker(tmp_path, [("usv.a", "float32")])
    b.start()
    assert b.alive()
    assert b.stop() == 0
