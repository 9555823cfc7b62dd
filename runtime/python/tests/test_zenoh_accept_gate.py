"""The accept gate of the SubBroker's zenoh listener (modd.zenoh_gate, docs/security.md
"Connections per source"): its per-source table (bounds, refill, bounded memory), its
relay (bytes both ways, the refusal line, no descriptor left behind) and what a client
is told when the gate turns its address away."""

from __future__ import annotations

import os
import socket
import socketserver
import threading
import time
from collections.abc import Iterator

import pytest
from modd.zenoh_gate import AcceptGate, parse_gated, start_gates
from modd.zenoh_gate_policy import REFUSAL_MARK, GateLimits, SourceTable, source_of
from modd.zenoh_session import ZenohSettings, is_gated, refusal, tcp_probe


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def test_pending_bound_and_settling() -> None:
    t = SourceTable(GateLimits(per_source_pending=3, per_source_rate=100), Clock())
    assert [t.admit("a") for _ in range(3)] == [None] * 3
    assert (t.admit("a") or "").startswith("per_source_pending: 3 connections of a")
    assert t.admit("b") is None  # another source is not held by a's
    t.settled("a")  # past its handshake time: no longer pending, still open
    assert t.admit("a") is None
    t.closed("a", was_pending=True)
    assert t.admit("a") is None


def test_rate_bound_refills() -> None:
    clock = Clock()
    t = SourceTable(GateLimits(per_source_pending=1000, per_source_rate=5), clock)
    admitted = sum(t.admit("a") is None for _ in range(50))
    assert admitted == 10  # the burst: twice the rate
    assert "per_source_rate" in (t.admit("a") or "")
    clock.t += 1.0
    assert sum(t.admit("a") is None for _ in range(50)) == 5
    assert t.due_report("a", 10.0) == 40 + 1 + 45 and t.due_report("a", 10.0) == 0


def test_the_source_table_is_bounded() -> None:
    clock = Clock()
    t = SourceTable(GateLimits(max_sources=64), clock)
    for i in range(10_000):  # a sweep of addresses, each closing at once
        assert t.admit(f"10.0.{i // 256}.{i % 256}") is None
        t.closed(f"10.0.{i // 256}.{i % 256}", was_pending=True)
        assert len(t) <= 64
    held = SourceTable(GateLimits(max_sources=4), clock)
    for i in range(4):  # sources with connections open are never forgotten
        assert held.admit(f"h{i}") is None
    assert (held.admit("new") or "").startswith("max_sources: 4")
    held.closed("h0", was_pending=True)
    assert held.admit("new") is None and len(held) == 4


def test_sources_and_limits() -> None:
    assert source_of("127.0.0.2") == "127.0.0.2"
    assert source_of("::ffff:127.1.2.3") == "127.1.2.3"
    assert source_of("2001:db8:1:2:aa::1") == source_of("2001:db8:1:2:bb::9") == "2001:db8:1:2::/64"
    got = ZenohSettings.from_mapping({"gate": {"per_source_pending": 8, "enabled": False}})
    assert got.gate == GateLimits(enabled=False, per_source_pending=8)
    assert ZenohSettings.from_mapping({}).gate == GateLimits()
    for bad, says in [
        ({"per_source": 1}, "unknown key 'per_source'"),
        ({"per_source_rate": True}, "per_source_rate: expected a number"),
        ({"per_source_pending": 0}, "per_source_pending: expected a number above 0"),
        ({"enabled": "yes"}, "enabled: expected true or false"),
    ]:
        with pytest.raises(ValueError, match=says):
            ZenohSettings.from_mapping({"gate": bad}, "sb.toml: zenoh")
    assert parse_gated("tcp/127.0.0.1:7447") == ("tcp", "127.0.0.1", 7447)
    assert parse_gated("tls/[::1]:7447") == ("tls", "::1", 7447)
    assert parse_gated("udp/127.0.0.1:7447") is None
    assert parse_gated("tcp/127.0.0.1:7447#iface=lo") is None


class Echo(socketserver.ThreadingTCPServer):
    daemon_threads = True
    allow_reuse_address = True


class EchoHandler(socketserver.BaseRequestHandler):
    def handle(self) -> None:
        while data := self.request.recv(65536):
            self.request.sendall(data)


@pytest.fixture
def echo() -> Iterator[tuple[str, int]]:
    server = Echo(("127.0.0.1", 0), EchoHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield server.server_address[:2]  # type: ignore[misc]
    finally:
        server.shutdown()
        server.server_close()


def fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def test_relay_refusal_line_and_no_leak(echo: tuple[str, int]) -> None:
    before = fds()
    limits = GateLimits(per_source_pending=2, per_source_rate=1000)
    gate = AcceptGate(("127.0.0.1", 0), echo, limits, pending_s=60).start()
    try:
        a, b = (socket.create_connection(gate.address, timeout=5) for _ in range(2))
        payload = os.urandom(1 << 20)
        a.sendall(payload)
        got = b""
        while len(got) < len(payload):
            got += a.recv(1 << 20)
        assert got == payload  # 1 MiB through the gate both ways, intact
        with socket.create_connection(gate.address, timeout=5) as c:  # a third, pending
            said = c.recv(512)
            assert said.startswith(REFUSAL_MARK) and b"per_source_pending" in said
        probe = tcp_probe(f"tcp/127.0.0.1:{gate.address[1]}")
        assert is_gated(probe) and "per_source_pending: 2 connections of 127.0.0.1" in str(probe)
        told = refusal(ZenohSettings(mode="client", connect=("tcp/127.0.0.1:1",)), probe, 10)
        assert "refuses new connections from this address" in told
        assert "credentials were not checked" in told and "refused the credentials" not in told
        a.close()
        time.sleep(0.3)
        with socket.create_connection(gate.address, timeout=5) as c:  # a slot again
            c.sendall(b"ping")
            assert c.recv(4) == b"ping"
        b.close()
    finally:
        gate.stop()
    deadline = time.monotonic() + 5  # the echo server's threads close their ends too
    while fds() > before and time.monotonic() < deadline:
        time.sleep(0.05)
    assert fds() <= before, "the gate left a descriptor open"


def test_start_gates_moves_zenoh_to_loopback() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        taken = ZenohSettings(mode="router", listen=(f"tcp/127.0.0.1:{port}",))
        with pytest.raises(ValueError, match=f"cannot listen on tcp/127.0.0.1:{port}"):
            start_gates(taken)
    s = ZenohSettings(mode="router", listen=("tcp/127.0.0.1:0", "udp/127.0.0.1:0"))
    inner, gates = start_gates(s)
    try:
        assert len(gates) == 1 and inner.listen[1] == "udp/127.0.0.1:0"
        assert inner.listen[0].startswith("tcp/127.0.0.1:") and inner.listen[0] != s.listen[0]
        assert gates[0].pending_s == 2.0  # the listener's accept_timeout
    finally:
        for g in gates:
            g.stop()
    off = ZenohSettings(mode="router", listen=("tcp/127.0.0.1:0",))
    off = ZenohSettings.from_mapping({"listen": list(off.listen), "gate": {"enabled": False}})
    assert start_gates(off) == (off, [])
