"""The SubBroker's TCP link measures the round trip on connect: a PubBroker that
streams DATA of its running config but never answers PING must not hold the
connection in that measurement for ever (the CONFIG would never go)."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from typing import Any

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
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.configs: list[Config] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.listener.accept()
        with conn:
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
                    if isinstance(msg, Ping) and self.pongs:
                        conn.sendall(codec.encode(Pong(msg.payload)))
                    elif isinstance(msg, Config):
                        self.configs.append(msg)
                        conn.sendall(codec.encode(ConfigAck(msg.config_id, 0, 2)))

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
