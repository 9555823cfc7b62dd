"""The thread that pumps a link session (subbroker/pump.py), over an in-memory
transport: what the pump writes goes to a PubBroker written with the
protocol's codec and proofs, its answers come back as what the pump reads.
Reconnection, the deploy path's CONFIG from another thread, a hook that
raises, stop. The UDP port's part of the peer binding is checked on loopback."""

from __future__ import annotations

import os
import queue
import socket
import threading
import time
from collections.abc import Callable, Iterator

import pytest
from modd.link import backfill as bf
from modd.link import codec
from modd.link.auth import client_proof, server_proof
from modd.link.datagram import DGRAM_HANDSHAKE, encode_handshake
from modd.link.frames import (
    VERSION,
    Aggregation,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    Hello,
    Ping,
    Pong,
    Status,
    StreamSpec,
    TopicSpec,
    ValueType,
)
from modd.link.receiver import Window
from modd.subbroker.config import LinkOptions
from modd.subbroker.dgport import UdpPort
from modd.subbroker.dgsession import DatagramSession
from modd.subbroker.linkhooks import LinkDown
from modd.subbroker.pump import Pump
from modd.subbroker.stream_session import StreamSession

KEY = b"the pump's link key, 32 bytes ok"
CONFIG = Config(
    9,
    0,
    (TopicSpec("usv.depth", ValueType.FLOAT32, 1),),
    (StreamSpec(0, Aggregation.MAX, 500_000),),
)
OPTIONS = LinkOptions(backoff_initial_s=0.01, backoff_max_s=0.05, ack_timeout_s=10.0)


class PubBroker:
    """Answers the handshake, PINGs and CONFIGs (unless ``ack`` is off); keeps the
    other frames it gets."""

    def __init__(self) -> None:
        self.splitter = codec.FrameSplitter()
        self.nonce = os.urandom(16)
        self.client_nonce = b""
        self.ack = True
        self.running = 0  # the config id AUTH_OK reports
        self.got: list[object] = []

    def answer(self, data: bytes) -> bytes:
        out = b""
        for f in self.splitter.feed(data):
            if bf.is_backfill_type(f.type):
                self.got.append(bf.decode(f))
                continue
            msg = codec.decode(f)
            self.got.append(msg)
            if isinstance(msg, Hello):
                self.splitter = codec.FrameSplitter()
                self.client_nonce = msg.nonce
                out += codec.encode(Challenge(VERSION, self.nonce))
            elif isinstance(msg, Auth):
                assert msg.mac == client_proof(KEY, self.client_nonce, self.nonce)
                mac = server_proof(KEY, self.client_nonce, self.nonce)
                out += codec.encode(AuthOk(mac, self.running, 1))
            elif isinstance(msg, Ping):
                out += codec.encode(Pong(msg.payload))
            elif isinstance(msg, Config) and self.ack:
                self.running = msg.config_id
                out += codec.encode(ConfigAck(msg.config_id, 0, 1))
        return out


class MemoryPump(Pump):
    """A pump whose connection is a queue to :class:`PubBroker`."""

    def __init__(self, handler: Handler) -> None:
        self.broker = PubBroker()
        self.inbox: queue.Queue[bytes | None] = queue.Queue()
        self.opens = 0
        self.refuse = 0  # opens still refused
        self.ups: list[int] = []
        super().__init__(StreamSession(KEY, OPTIONS, handler), OPTIONS, "memory", "test-link")

    def _open(self) -> None:
        self.opens += 1
        if self.refuse:
            self.refuse -= 1
            raise ConnectionRefusedError("refused")
        self.broker.splitter = codec.FrameSplitter()

    def _read(self) -> None:
        try:
            data = self.inbox.get(timeout=0.01)
        except queue.Empty:
            return
        if data is None:
            raise LinkDown("the PubBroker closed the link")
        assert isinstance(self.session, StreamSession)
        self.session.feed(data)

    def _write(self, data: bytes) -> None:
        reply = self.broker.answer(data)
        if reply:
            self.inbox.put(reply)

    def _close(self, stopping: bool) -> None:
        while not self.inbox.empty():
            self.inbox.get_nowait()


class Handler:
    def __init__(self) -> None:
        self.config: Config | None = CONFIG
        self.connects = 0
        self.acked: list[int] = []
        self.fail_status = False

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | None:
        self.connects += 1
        return self.config if ok.config_id != CONFIG.config_id else None

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None:
        self.acked.append(config.config_id)

    def on_windows(self, windows: list[Window]) -> None:
        pass

    def on_status(self, status: object) -> None:
        raise RuntimeError("a bug in the SubBroker")


def _until(check: Callable[[], bool], what: str, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < deadline, what
        time.sleep(0.01)


@pytest.fixture
def pump() -> Iterator[MemoryPump]:
    p = MemoryPump(Handler())
    p.on_up = lambda: p.ups.append(1)
    p.start()
    yield p
    p.stop()


def test_it_connects_configures_and_sends_from_any_thread(pump: MemoryPump) -> None:
    _until(lambda: pump.stats.state == "up", "the link comes up")
    handler = pump.session.handler
    assert isinstance(handler, Handler) and handler.acked == [9] and pump.up
    assert pump.send_config(Config(10, 0, CONFIG.topics, CONFIG.streams), 5.0).config_id == 10
    pump.send_frame(bf.encode(bf.BackfillCancel(4)))
    _until(lambda: bf.BackfillCancel(4) in pump.broker.got, "the cancel reaches the broker")
    assert pump.stats.bytes_out > 0 and pump.radio_status() is None


def test_a_dropped_link_fails_what_waits_and_comes_back(pump: MemoryPump) -> None:
    _until(lambda: pump.stats.state == "up", "the link comes up")
    pump.broker.ack = False
    result: list[BaseException] = []

    def deploy() -> None:
        try:
            pump.send_config(Config(11, 0, CONFIG.topics, CONFIG.streams), 5.0)
        except BaseException as exc:  # noqa: BLE001 - what the deploy thread sees
            result.append(exc)

    t = threading.Thread(target=deploy)
    t.start()
    _until(
        lambda: any(isinstance(m, Config) and m.config_id == 11 for m in pump.broker.got),
        "the CONFIG is sent",
    )
    pump.refuse = 2  # the next two connects are refused: backoff, then it comes back
    pump.inbox.put(None)
    t.join(5.0)
    assert len(result) == 1 and isinstance(result[0], LinkDown)
    _until(lambda: pump.opens >= 4 and pump.stats.state == "up", "the link comes back")
    assert pump.stats.connects == 2 and pump.ups == [1, 1]
    assert pump.stats.last_error == "refused"


def test_a_bug_in_a_hook_is_logged_and_the_link_reconnects(pump: MemoryPump) -> None:
    _until(lambda: pump.stats.state == "up", "the link comes up")
    pump.inbox.put(codec.encode(Status((1,))))
    _until(lambda: pump.stats.connects == 2, "reconnected after the bug")
    assert pump.stats.last_error == "internal error: a bug in the SubBroker"


def test_stop_ends_the_thread_and_the_link() -> None:
    p = MemoryPump(Handler())
    p.start()
    _until(lambda: p.up, "the link comes up")
    p.stop()
    assert p.stats.state == "stopped" and not p.up and not p._thread.is_alive()
    with pytest.raises(LinkDown, match="the link to memory is down"):
        p.send_frame(b"\x01\x06")


def test_the_udp_port_reports_each_datagrams_source_and_the_session_binds_to_it() -> None:
    """On loopback: the PubBroker at 127.0.0.1, a stranger at 127.0.0.2 writing to the
    base station's port. Both reach the port; the session reads only the PubBroker's."""
    drone = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    stranger = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    with drone, stranger:
        drone.bind(("127.0.0.1", 0))
        stranger.bind(("127.0.0.2", 0))
        port = UdpPort(("localhost", drone.getsockname()[1]))
        try:
            session = DatagramSession("udp", KEY, OPTIONS, Handler())
            session.expect(port.peer)
            session.begin()
            (hello,) = session.take()
            port.send(hello)
            data, base = drone.recvfrom(2048)
            assert data[0] == DGRAM_HANDSHAKE
            challenge = encode_handshake(codec.encode(Challenge(VERSION, os.urandom(16))))
            stranger.sendto(challenge, base)
            drone.sendto(challenge, base)
            got: list[tuple[bytes, object]] = []
            _until(lambda: len(got.__iadd__(port.recv(0.05))) >= 2, "both datagrams arrive")
            assert sorted(str(src) for _, src in got) == sorted(
                [
                    str(("127.0.0.1", drone.getsockname()[1])),
                    str(("127.0.0.2", stranger.getsockname()[1])),
                ]
            )
            for raw, src in got:
                session.datagram(raw, src)
            assert session.radio.foreign == 1 and len(session.take()) == 1  # one AUTH
        finally:
            port.close()
