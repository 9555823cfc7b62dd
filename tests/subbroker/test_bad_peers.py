"""Bad peers on the link are rejected and logged, and nobody stops serving:
garbage and a wrong key sent to the real PubBroker while the SubBroker is
delivering; a PubBroker impostor without the key, and one that sends
malformed frames, met by the SubBroker."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from modd.link import codec
from modd.link.auth import client_handshake, server_proof
from modd.link.frames import VERSION, AuthOk, Challenge, ProtocolError
from modd.zenoh_session import wait_connected
from subbroker_harness import (
    KEY,
    assert_contiguous,
    free_port,
    model_copy,
    processes,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector


@pytest.mark.usefixtures("needs_pubbroker")
def test_pubbroker_rejects_garbage_and_wrong_key_and_keeps_serving(
    tmp_path: Path, zenoh_client: Any
) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp_path, "scenario1.modd")
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport))
    load = start_load(tmp_path, model, ingress, 7)
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("running", 10)
        time.sleep(1.5)
        with socket.create_connection(("127.0.0.1", link), 2) as s:
            s.sendall(b"\x05\xff\xfe\xfd\xfc\xfb garbage")
            s.settimeout(3)
            with contextlib.suppress(OSError):
                while s.recv(4096):
                    pass  # closed by the PubBroker (maybe after an ERROR frame)
        with socket.create_connection(("127.0.0.1", link), 2) as s:
            s.settimeout(3)
            with pytest.raises((ProtocolError, ConnectionError)):
                client_handshake(s, b"not the key")
        load.p.wait(15)
        time.sleep(0.6)
    finally:
        with processes(pb, sb, load):
            pass
    assert pb.alive() is False and "auth" in pb.log().lower()
    status = got.status[-1]
    assert status["connects"] == 1, status  # the real link was never disturbed
    values = [v for v in got.snapshot()["sub_5"] if v.value is not None]
    assert len(values) >= 20
    assert_contiguous(values, 250_000_000)


class Impostor(threading.Thread):
    """Listens where the SubBroker expects the PubBroker. ``key``: the key it
    holds; ``then``: bytes it sends after a successful handshake."""

    def __init__(self, key: bytes, then: bytes = b"") -> None:
        super().__init__(daemon=True)
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.key, self.then = key, then
        self.connections = 0
        self.stop = False

    def run(self) -> None:
        self.server.settimeout(0.1)
        while not self.stop:
            try:
                conn, _ = self.server.accept()
            except OSError:
                continue
            self.connections += 1
            with conn, contextlib.suppress(OSError, ProtocolError):
                conn.settimeout(2)
                self._serve(conn)
        self.server.close()

    def _serve(self, conn: socket.socket) -> None:
        splitter = codec.FrameSplitter()
        frames: list[codec.RawFrame] = []
        while not frames:
            frames = splitter.feed(conn.recv(4096))
        hello = codec.decode(frames[0])
        nonce = os.urandom(16)
        conn.sendall(codec.encode(Challenge(VERSION, nonce)))
        frames = []
        while not frames:
            frames = splitter.feed(conn.recv(4096))
        mac = server_proof(self.key, hello.nonce, nonce)  # type: ignore[union-attr]
        conn.sendall(codec.encode(AuthOk(mac, 0, 0)))
        conn.sendall(self.then)
        with contextlib.suppress(OSError):
            while conn.recv(4096):
                pass


@pytest.mark.parametrize("case", ["wrong_key", "malformed"])
def test_subbroker_rejects_an_impostor_and_keeps_trying(tmp_path: Path, case: str) -> None:
    if case == "wrong_key":
        imp = Impostor(b"someone else's key")
        expected = "does not know the key"
    else:  # right key, then a frame of an unknown type and a bad length
        imp = Impostor(KEY.encode(), then=b"\x02\x6e\x00" + b"\xff" * 12)
        expected = "unknown message type"
    imp.start()
    model = model_copy(tmp_path, "scenario1.modd")
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, imp.port, free_port()))
    try:
        assert sb.wait_log(expected, 10), sb.log()
        deadline = time.monotonic() + 10
        while imp.connections < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert imp.connections >= 3  # it retries with backoff
        assert sb.alive()
    finally:
        imp.stop = True
        sb.stop()
        imp.join(2)
