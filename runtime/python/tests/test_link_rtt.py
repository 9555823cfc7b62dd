"""The SubBroker's TCP link measures the round trip on connect: a PubBroker that
streams DATA of its running config but never answers PING must not hold the
connection in that measurement for ever (the CONFIG would never go). With
``ping_period_s`` it keeps measuring: the RTT follows a link that slows down."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from typing import Any

import pytest
from modd.link import codec
from modd.link.auth import client_proof, read_frame, server_proof
from modd.link.frames import VERSION, Auth, AuthOk, Challenge, Config, ConfigAck, Hello, Ping, Pong
from modd.subbroker.config import LinkOptions
from modd.subbroker.link import LinkClient

KEY = b"rtt-test-key"


def _sync_data(config_id: int, slot: int) -> bytes:
    """A sync DATA frame header of a config the client never sent (skipped there)."""
    return codec._frame(0x12, bytes([config_id]) + codec.varint(slot))


class _SilentPubBroker:
    """Handshakes, then sends DATA every 50 ms; PING gets a PONG only when ``pongs``."""

    def __init__(self, pongs: bool) -> None:
        self.pongs = pongs
        self.pong_delay_s = 0.0
        self.pings = 0
        self._due: list[tuple[float, bytes]] = []
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.configs: list[Config] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.listener.accept()
        # The client may close first (the test ends): a write to it then is the end, not an error.
        with conn, contextlib.suppress(BrokenPipeError, ConnectionResetError):
            splitter = codec.FrameSplitter()
            hello = codec.decode(read_frame(conn, splitter))
            assert isinstance(hello, Hello)
            server_nonce = os.urandom(16)
            conn.sendall(codec.encode(Challenge(VERSION, server_nonce)))
            auth = codec.decode(read_frame(conn, splitter))
            assert isinstance(auth, Auth)
            assert auth.mac == client_proof(KEY, hello.nonce, server_nonce)
            conn.sendall(codec.encode(AuthOk(server_proof(KEY, hello.nonce, server_nonce), 7, 1)))
            conn.settimeout(0.05)
            slot = 0
            while not self.stop.is_set():
                slot += 1
                conn.sendall(_sync_data(7, slot))
                with contextlib.suppress(TimeoutError):
                    data = conn.recv(4096)
                    if not data:
                        return
                    splitter.buf += data
                while (frame := splitter.pop()) is not None:
                    msg = codec.decode(frame)
                    if isinstance(msg, Ping):
                        self.pings += 1
                        if self.pongs:
                            self._due.append((time.monotonic() + self.pong_delay_s, msg.payload))
                    elif isinstance(msg, Config):
                        self.configs.append(msg)
                        conn.sendall(codec.encode(ConfigAck(msg.config_id, 0, 2)))
                now = time.monotonic()
                for due, payload in [d for d in self._due if d[0] <= now]:
                    self._due.remove((due, payload))
                    conn.sendall(codec.encode(Pong(payload)))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        self.listener.close()


class _Handler:
    def __init__(self) -> None:
        self.rtts: list[float | None] = []

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | None:
        self.rtts.append(rtt_s)
        return None

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None: ...

    def on_windows(self, windows: Any) -> None: ...

    def on_status(self, status: Any) -> None: ...


def _connect(pongs: bool) -> tuple[_Handler, float]:
    server = _SilentPubBroker(pongs)
    handler = _Handler()
    options = LinkOptions(connect_timeout_s=0.3, ping_count=3)
    client = LinkClient(("127.0.0.1", server.port), KEY, options, handler)
    began = time.monotonic()
    client.start()
    try:
        deadline = began + 10
        while not handler.rtts and time.monotonic() < deadline:
            time.sleep(0.01)
        return handler, time.monotonic() - began
    finally:
        client.stop()
        server.close()


def test_a_pubbroker_that_never_pongs_does_not_hold_the_connection() -> None:
    handler, took = _connect(pongs=False)
    assert handler.rtts == [None], "on_connect never ran: the RTT measurement did not end"
    assert took < 5, took  # three PINGs of at most 0.3 s each


def test_the_round_trip_is_measured_when_the_pubbroker_answers() -> None:
    handler, _ = _connect(pongs=True)
    assert len(handler.rtts) == 1 and handler.rtts[0] is not None and handler.rtts[0] < 0.3


def test_periodic_pings_follow_a_link_that_slows_down() -> None:
    server = _SilentPubBroker(pongs=True)
    handler = _Handler()
    client = LinkClient(
        ("127.0.0.1", server.port),
        KEY,
        LinkOptions(connect_timeout_s=2.0, ping_period_s=0.1),
        handler,
    )
    client.start()
    try:
        deadline = time.monotonic() + 10
        while not handler.rtts and time.monotonic() < deadline:
            time.sleep(0.01)
        assert handler.rtts and handler.rtts[0] is not None and handler.rtts[0] < 0.25
        server.pong_delay_s = 0.4  # the radio slows down
        while time.monotonic() < deadline:
            rtt = client.stats.rtt_s
            if rtt is not None and rtt >= 0.35:
                break
            time.sleep(0.05)
        assert client.stats.rtt_s is not None and client.stats.rtt_s >= 0.35, client.stats
    finally:
        client.stop()
        server.close()


def test_without_a_ping_period_the_link_stays_quiet() -> None:
    server = _SilentPubBroker(pongs=True)
    handler = _Handler()
    client = LinkClient(("127.0.0.1", server.port), KEY, LinkOptions(ping_count=3), handler)
    client.start()
    try:
        deadline = time.monotonic() + 10
        while not handler.rtts and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(1.0)  # DATA flows every 50 ms: no silence PING either
        assert server.pings == 3
    finally:
        client.stop()
        server.close()


def test_round_trips_keep_the_median_of_the_recent_pongs_and_bound_those_awaited() -> None:
    from modd.subbroker.link import RoundTrips

    assert RoundTrips(0.0).due(100.0) is None  # off
    rt = RoundTrips(1.0, keep=3, in_flight=2)
    rt.restart(0.0)
    assert rt.due(0.5) is None
    first = rt.due(1.0)
    assert first is not None and rt.due(1.5) is None
    second, third = rt.due(2.0), rt.due(3.0)
    assert second is not None and third is not None
    assert rt.on_pong(first, 3.1) is None  # forgotten: only two are awaited
    assert rt.on_pong(b"not ours", 3.1) is None
    assert rt.on_pong(second, 2.5) == 0.5
    assert rt.on_pong(third, 3.1) == pytest.approx(0.3)  # the median of 0.5 and 0.1
    assert rt.on_pong(third, 3.2) is None  # answered once
