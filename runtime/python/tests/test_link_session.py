"""The SubBroker's link session, driven without a socket, a port or a thread:
bytes or datagrams in, bytes or datagrams out, a clock moved by hand; over a
byte stream (tcp) and over datagrams (udp, serial). The PubBroker's side is the
protocol's own code: the codec and the proofs (modd.link.codec, modd.link.auth,
held to the C++ PubBroker's by the shared vectors), the datagram tags, and the
Python DatagramSender that packs slots and answers NACKs from its ring."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import pytest
from modd.link import backfill as bf
from modd.link import codec
from modd.link.auth import client_proof, server_proof
from modd.link.datagram import (
    BASE_TO_DRONE,
    DGRAM_HANDSHAKE,
    DRONE_TO_BASE,
    encode_control,
    encode_handshake,
    session_key,
    verify_control,
)
from modd.link.dgreceiver import DatagramSender
from modd.link.frames import (
    VERSION,
    Aggregation,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    Data,
    ErrorCode,
    ErrorMsg,
    Hello,
    Message,
    Ping,
    Pong,
    ProtocolError,
    SensorHealth,
    Status,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
)
from modd.link.receiver import Window
from modd.subbroker.config import LinkOptions
from modd.subbroker.dgsession import RETRIES, DatagramSession
from modd.subbroker.linkhooks import ConfigRejected, LinkDown
from modd.subbroker.stream_session import StreamSession

PSK = b"a link key of the test, 32 bytes"
CONFIG = Config(
    3,
    0,
    (TopicSpec("usv.water.temp", ValueType.FLOAT32, 1),),
    (StreamSpec(0, Aggregation.AVERAGE, 250_000),),
)


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0
        self.wall_ns = 1_700_000_000 * 10**9

    def monotonic(self) -> float:
        return self.now

    def time_ns(self) -> int:
        return self.wall_ns

    def advance(self, s: float) -> None:
        self.now += s
        self.wall_ns += int(s * 1e9)


@dataclass
class Handler:
    """The SubBroker's side of the events, recorded."""

    config: Config | None = CONFIG
    connects: list[tuple[AuthOk, float | None]] = field(default_factory=list)
    acked: list[tuple[Config, ConfigAck]] = field(default_factory=list)
    windows: list[list[Window]] = field(default_factory=list)
    statuses: list[object] = field(default_factory=list)

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | None:
        self.connects.append((ok, rtt_s))
        return self.config

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None:
        self.acked.append((config, ack))

    def on_windows(self, windows: list[Window]) -> None:
        self.windows.append(windows)

    def on_status(self, status: object) -> None:
        self.statuses.append(status)


class PeerHandshake:
    """The PubBroker's answers to HELLO and AUTH, as docs/protocol.md, "Handshake"."""

    def __init__(self, key: bytes = PSK) -> None:
        self.key = key
        self.nonce = os.urandom(16)
        self.client_nonce = b""

    def challenge(self, hello: Message) -> bytes:
        assert isinstance(hello, Hello) and hello.version == VERSION
        self.client_nonce = hello.nonce
        return codec.encode(Challenge(VERSION, self.nonce))

    def auth_ok(self, auth: Message, config_id: int = 0, epoch_ns: int = 0) -> bytes:
        assert isinstance(auth, Auth)
        assert auth.mac == client_proof(self.key, self.client_nonce, self.nonce)
        mac = server_proof(self.key, self.client_nonce, self.nonce)
        return codec.encode(AuthOk(mac, config_id, epoch_ns))


def frames(data: list[bytes]) -> list[Message]:
    """The link frames in what a stream session emitted, decoded."""
    splitter = codec.FrameSplitter()
    return [codec.decode(f) for f in splitter.feed(b"".join(data))]


# -- over a byte stream (tcp) --------------------------------------------------


def _session(
    handler: Handler | None = None, liveness_s: float = 3.0, **opts: float
) -> tuple[StreamSession, FakeClock]:
    clock = FakeClock()
    options = LinkOptions(**opts)  # type: ignore[arg-type]
    return StreamSession(PSK, options, handler or Handler(), lambda: liveness_s, clock), clock


def _authenticate(
    s: StreamSession, clock: FakeClock, peer: PeerHandshake, config_id: int = 0, rtt_s: float = 0.04
) -> None:
    """HELLO, CHALLENGE, AUTH, AUTH_OK, then every PING answered ``rtt_s`` later."""
    s.begin()
    (hello,) = frames(s.take())
    s.feed(peer.challenge(hello))
    (auth,) = frames(s.take())
    s.feed(peer.auth_ok(auth, config_id, 5_000))
    for _ in range(3):
        (ping,) = frames(s.take())
        assert isinstance(ping, Ping)
        clock.advance(rtt_s)
        s.feed(codec.encode(Pong(ping.payload)))


def _data(slot: int, value: float, config: Config = CONFIG) -> bytes:
    return codec.encode_data(
        Data(True, config.config_id, slot, slot & 0xFF, [Value(True, value, 0, 4)]), config.kinds()
    )


def test_handshake_rtt_config_and_up() -> None:
    handler = Handler()
    s, clock = _session(handler)
    ups: list[bool] = []
    s.on_up = lambda: ups.append(s.up)
    _authenticate(s, clock, PeerHandshake(), rtt_s=0.04)
    assert s.stats.connects == 1 and s.stats.rtt_s == pytest.approx(0.04)
    assert [rtt for _, rtt in handler.connects] == [pytest.approx(0.04)]
    (config,) = frames(s.take())
    assert config == CONFIG and s.stats.state == "configuring" and ups == [True]
    s.feed(codec.encode(ConfigAck(3, 0, 7_000)))
    assert handler.acked == [(CONFIG, ConfigAck(3, 0, 7_000))] and s.stats.state == "up"


def test_a_broker_without_the_key_is_refused() -> None:
    s, _ = _session()
    s.begin()
    (hello,) = frames(s.take())
    peer = PeerHandshake()
    s.feed(peer.challenge(hello))
    frames(s.take())  # AUTH
    # a broker that does not hold our key cannot prove it back
    forged = AuthOk(server_proof(b"another key", peer.client_nonce, peer.nonce), 0, 0)
    with pytest.raises(ProtocolError, match="does not know the key") as exc:
        s.feed(codec.encode(forged))
    assert exc.value.code == ErrorCode.AUTH_FAILED and not s.up and s.stats.connects == 0


def test_refusals_and_strangers_in_the_handshake() -> None:
    s, _ = _session()
    s.begin()
    s.take()
    with pytest.raises(ProtocolError, match="broker refused HELLO: busy"):
        s.feed(codec.encode(ErrorMsg(ErrorCode.AUTH_FAILED, "busy")))
    s.begin()
    s.take()
    with pytest.raises(ProtocolError, match="expected CHALLENGE, got Pong") as exc:
        s.feed(codec.encode(Pong(b"x")))
    assert exc.value.code == ErrorCode.BAD_FRAME


def test_no_answer_to_hello_ends_the_session_after_the_connect_timeout() -> None:
    s, clock = _session(connect_timeout_s=2.0)
    s.begin()
    assert isinstance(frames(s.take())[0], Hello)
    clock.advance(1.9)
    s.tick()
    assert s.take() == []  # one try over a stream: no HELLO again
    clock.advance(0.2)
    with pytest.raises(LinkDown, match="no answer to HELLO"):
        s.tick()


def test_a_missing_pong_is_skipped_and_the_plan_keeps_the_models_rtt() -> None:
    handler = Handler()
    s, clock = _session(handler, connect_timeout_s=1.0)
    peer = PeerHandshake()
    s.begin()
    s.feed(peer.challenge(frames(s.take())[0]))
    s.feed(peer.auth_ok(frames(s.take())[0]))
    for _ in range(3):
        (ping,) = frames(s.take())
        assert isinstance(ping, Ping)
        s.feed(_data(0, 1.0))  # DATA of a config it never sent: skipped, never fatal
        clock.advance(1.01)
        s.tick()
    assert handler.connects[0][1] is None and s.stats.bad_frames == 3 and s.up


def test_config_rejected_by_status_and_by_error() -> None:
    handler = Handler(config=None)  # resume what runs
    s, clock = _session(handler)
    _authenticate(s, clock, PeerHandshake(), config_id=3)
    assert s.stats.state == "up" and s.take() == []
    refused = s.submit(CONFIG)
    s.feed(codec.encode(ConfigAck(3, 2, 0)))
    exc = refused.exception(timeout=0)
    assert isinstance(exc, ConfigRejected) and exc.status == 2
    erred = s.submit(CONFIG)
    s.feed(codec.encode(ErrorMsg(ErrorCode.BAD_CONFIG, "too many topics")))
    exc = erred.exception(timeout=0)
    assert isinstance(exc, ConfigRejected) and "too many topics" in str(exc)
    assert s.stats.last_error == f"PubBroker error {ErrorCode.BAD_CONFIG:d}: too many topics"
    assert handler.acked == []


def test_config_ack_timeout() -> None:
    """A deploy's CONFIG unanswered fails its future and keeps the link; the one
    sent on connect drops the link."""
    s, clock = _session(Handler(config=None), ack_timeout_s=5.0)
    _authenticate(s, clock, PeerHandshake(), config_id=3)
    late = s.submit(CONFIG)
    clock.advance(5.1)
    s.feed(codec.encode(Ping(b"p")))  # the PubBroker is there
    s.tick()
    assert isinstance(late.exception(timeout=0), TimeoutError) and s.up
    s2, clock2 = _session(ack_timeout_s=5.0)
    _authenticate(s2, clock2, PeerHandshake())
    clock2.advance(5.1)
    with pytest.raises(LinkDown, match="no CONFIG_ACK for config 3"):
        s2.tick()


def test_pings_are_answered_and_periodic_pings_measure_the_rtt() -> None:
    handler = Handler(config=None)
    s, clock = _session(handler, liveness_s=60.0, ping_period_s=10.0)
    _authenticate(s, clock, PeerHandshake(), config_id=3, rtt_s=0.05)
    s.feed(codec.encode(Ping(b"hi")))
    assert frames(s.take()) == [Pong(b"hi")]
    clock.advance(10.0)
    s.tick()
    (ping,) = frames(s.take())
    assert isinstance(ping, Ping)
    clock.advance(0.3)
    s.feed(codec.encode(Pong(ping.payload)))
    assert s.stats.rtt_s == pytest.approx(0.3)


def test_data_frames_become_windows_and_backfill_goes_to_the_sink() -> None:
    handler = Handler()
    s, clock = _session(handler)
    got: list[object] = []
    s.backfill_sink = lambda f: got.append(bf.decode(f))
    _authenticate(s, clock, PeerHandshake())
    s.feed(codec.encode(ConfigAck(3, 0, 10**18)))
    end = bf.encode(bf.BackfillEnd(7, bf.EndStatus.DONE, 55))
    s.feed(_data(0, 1.5) + _data(1, 2.5) + end)
    assert [(w.slot, w.value.number, w.end_ns) for (w,) in handler.windows] == [
        (0, 1.5, 10**18 + 250_000_000),
        (1, 2.5, 10**18 + 500_000_000),
    ]
    assert got == [bf.BackfillEnd(7, bf.EndStatus.DONE, 55)]
    assert s.stats.data_frames == 2 and s.stats.last_data_ns == clock.wall_ns
    s.feed(codec.encode(Status((11, 22, 33))))
    assert handler.statuses == [Status((11, 22, 33))]
    assert list(s.stats.pubbroker.values()) == [11, 22, 33]
    assert s.stats.sensors == {}
    gnss = SensorHealth("gnss", (1, 40, 2, 1, 1700, 80, 0, 0, 0, 0, 3, 9, 4, 7))
    s.feed(codec.encode(Status((11,), (gnss,))))
    assert s.stats.sensors == {
        "gnss": {
            "state": 1,
            "lines_ok": 40,
            "lines_bad": 2,
            "reconnects": 1,
            "last_value_ms": 1700,
            "values": 80,
            "missing": 0,
            "refused": 0,
            "timeouts": 0,
            "exceptions": 0,
            "silences": 3,
            "ignored": 9,
            "no_fix": 4,
            "field_13": 7,  # a field a newer modd-sensors appends: kept by position
        }
    }


def test_silence_gets_one_ping_then_ends_the_session() -> None:
    s, clock = _session(Handler(config=None))  # liveness 3 s
    _authenticate(s, clock, PeerHandshake(), config_id=3)
    clock.advance(1.6)
    s.tick()
    assert frames(s.take()) == [Ping(b"alive")]
    clock.advance(1.0)
    s.tick()
    assert s.take() == []  # one PING per silence
    clock.advance(0.5)
    with pytest.raises(LinkDown, match="no frame for 3.1 s"):
        s.tick()


def test_reconnect_fails_what_waits_and_resumes_the_running_config() -> None:
    handler = Handler()
    s, clock = _session(handler)
    _authenticate(s, clock, PeerHandshake())
    s.feed(codec.encode(ConfigAck(3, 0, 10**18)) + _data(0, 1.0))
    waiting = s.submit(Config(4, 0, CONFIG.topics, CONFIG.streams))
    s.close("link down")
    assert isinstance(waiting.exception(timeout=0), LinkDown) and not s.up
    assert s.stats.state == "down"
    with pytest.raises(LinkDown):
        s.send_frame(b"\x01\x06")
    handler.config = None  # AUTH_OK reports config 3 still running: resumed
    _authenticate(s, clock, PeerHandshake(), config_id=3)
    assert s.stats.connects == 2 and s.stats.state == "up" and s.take() == []
    s.feed(_data(1, 2.0))
    assert [w.value.number for (w,) in handler.windows] == [1.0, 2.0]


# -- over datagrams (udp, serial) ---------------------------------------------

DRONE = ("127.0.0.1", 7171)
STRANGER = ("127.0.0.9", 7171)


class Drone:
    """The PubBroker's end: handshake, control datagrams, DATA from a sender."""

    def __init__(self) -> None:
        self.peer = PeerHandshake()
        self.key = b""
        self.counter = 0
        self.sender: DatagramSender | None = None

    def handshake(self, raw: bytes, config_id: int = 0) -> bytes:
        assert raw[0] == DGRAM_HANDSHAKE
        f = codec.split_frame(raw[1:])
        assert f is not None
        msg = codec.decode(f)
        if isinstance(msg, Hello):
            return encode_handshake(self.peer.challenge(msg))
        self.key = session_key(PSK, self.peer.client_nonce, self.peer.nonce)
        return encode_handshake(self.peer.auth_ok(msg, config_id, 0))

    def control(self, frame: bytes) -> bytes:
        self.counter += 1
        return encode_control(self.counter, frame, self.key, DRONE_TO_BASE)

    def read(self, raw: bytes) -> Message:
        _, frame = verify_control(raw, self.key, BASE_TO_DRONE)
        f = codec.split_frame(frame)
        assert f is not None
        return codec.decode(f)


def _authenticated(
    handler: Handler | None = None, config_id: int = 0, options: LinkOptions | None = None
) -> tuple[DatagramSession, FakeClock, Drone]:
    clock = FakeClock()
    s = DatagramSession(
        "udp",
        PSK,
        options or LinkOptions(),
        handler or Handler(),
        delay_s=1.0,
        liveness_s=lambda: 3.0,
        clock=clock,
        peer=DRONE,
    )
    drone = Drone()
    s.begin()
    (hello,) = s.take()
    s.datagram(drone.handshake(hello), DRONE)
    (auth,) = s.take()
    s.datagram(drone.handshake(auth, config_id), DRONE)
    for _ in range(3):
        (ping,) = s.take()
        msg = drone.read(ping)
        assert isinstance(msg, Ping)
        clock.advance(0.1)
        s.datagram(drone.control(codec.encode(Pong(msg.payload))), DRONE)
    return s, clock, drone


def _slot(value: float) -> bytes:
    return codec.encode_data(Data(False, 0, 0, 0, [Value(True, value, 0, 2)]), CONFIG.kinds())[3:]


def test_hello_is_sent_every_second_ten_times_then_the_session_ends() -> None:
    clock = FakeClock()
    s = DatagramSession("serial", PSK, LinkOptions(), Handler(), clock=clock)
    s.begin()
    sent = s.take()
    for _ in range(RETRIES - 1):
        clock.advance(1.0)
        s.tick()
        sent += s.take()
    assert len(sent) == RETRIES and len(set(sent)) == 1 and sent[0][0] == DGRAM_HANDSHAKE
    clock.advance(1.0)
    with pytest.raises(LinkDown, match="no answer to HELLO after 10 tries"):
        s.tick()


def test_handshake_rtt_and_a_config_resent_until_its_ack() -> None:
    handler = Handler()
    s, clock, drone = _authenticated(handler)
    assert s.stats.rtt_s == pytest.approx(0.1) and s.radio.handshakes == 1
    (config,) = s.take()
    assert drone.read(config) == CONFIG  # under the session key derived from the nonces
    clock.advance(1.0)
    s.tick()
    resent = s.take()
    assert [drone.read(d) for d in resent] == [CONFIG]
    s.datagram(drone.control(codec.encode(ConfigAck(3, 0, 10**18))), DRONE)
    clock.advance(1.0)
    s.tick()
    assert s.take() == [] and handler.acked[0][1].epoch_ns == 10**18 and s.stats.state == "up"


def test_a_config_unacked_after_ten_tries_drops_the_link() -> None:
    s, clock, drone = _authenticated(options=LinkOptions(ack_timeout_s=60.0))
    sent = s.take()
    for _ in range(RETRIES - 1):
        clock.advance(1.0)
        s.datagram(drone.control(codec.encode(Ping(b"x"))), DRONE)  # the PubBroker is there
        s.tick()
        sent += s.take()
    assert [drone.read(d) for d in sent].count(CONFIG) == RETRIES
    clock.advance(1.0)
    with pytest.raises(LinkDown, match="no CONFIG_ACK for config 3"):
        s.tick()


def test_a_config_unacked_within_the_ack_timeout_drops_the_link() -> None:
    s, clock, drone = _authenticated(options=LinkOptions(ack_timeout_s=2.5))
    clock.advance(2.0)
    s.tick()
    clock.advance(0.6)
    with pytest.raises(LinkDown, match="no CONFIG_ACK for config 3"):
        s.tick()


def _running(handler: Handler) -> tuple[DatagramSession, FakeClock, Drone, DatagramSender]:
    s, clock, drone = _authenticated(handler)
    s.take()
    epoch = clock.wall_ns
    s.datagram(drone.control(codec.encode(ConfigAck(3, 0, epoch))), DRONE)
    return s, clock, drone, DatagramSender(drone.key, 3, delay_s=1.0, room=10)  # 2 slots each


def test_a_lost_datagram_is_nacked_and_its_resend_delivered() -> None:
    """Three datagrams of two slots; the second is lost on the radio: the session
    NACKs its slots, the PubBroker's ring answers, every value arrives once."""
    handler = Handler()
    s, clock, drone, sender = _running(handler)
    out = []
    for k in range(6):
        out += sender.add_slot(k, k * 0.25, _slot(float(k)))
    out.append(sender.flush())
    assert len(out) == 3
    clock.advance(0.5)
    s.datagram(out[0], DRONE)
    s.datagram(out[2], DRONE)
    clock.advance(0.5)
    s.tick()
    nacks = s.take()
    resends = [d for n in nacks for d in sender.on_control(n)]
    assert resends == [out[1]] and s.radio.nacks >= 1
    s.datagram(resends[0], DRONE)
    values = sorted((w.slot, w.value.number) for ws in handler.windows for w in ws)
    assert values == [(k, float(k)) for k in range(6)]
    s.datagram(out[0], DRONE)  # replayed
    assert s.radio.replayed == 1 and len(handler.windows) == 6
    forged = bytearray(out[2])
    forged[-1] ^= 1
    assert not s.datagram(bytes(forged), DRONE) and s.radio.forged == 1
    status = s.radio_status()
    assert (status["slots_received"], status["forged"], status["replayed"]) == (6, 1, 1)


def test_after_authentication_the_session_is_bound_to_its_peer() -> None:
    """A datagram from another address is dropped and counted, not processed, even
    one that would verify (a stranger relaying the PubBroker's)."""
    handler = Handler()
    s, clock, drone, sender = _running(handler)
    (d,) = sender.add_slot(0, 0.0, _slot(1.0)) + [sender.flush()]
    assert not s.datagram(d, STRANGER)
    end = drone.control(bf.encode(bf.BackfillEnd(7, bf.EndStatus.DONE, 1)))
    got: list[object] = []
    s.backfill_sink = got.append
    assert not s.datagram(end, STRANGER)
    assert s.radio.foreign == 2 and handler.windows == [] and got == []
    assert s.datagram(d, DRONE) and s.datagram(end, DRONE)
    assert len(handler.windows) == 1 and len(got) == 1


def test_before_authentication_a_strangers_challenge_is_not_answered() -> None:
    clock = FakeClock()
    s = DatagramSession("udp", PSK, LinkOptions(), Handler(), clock=clock, peer=DRONE)
    s.begin()
    (hello,) = s.take()
    stranger = Drone()
    s.datagram(stranger.handshake(hello), STRANGER)
    assert s.take() == [] and s.radio.foreign == 1  # no AUTH on a stranger's nonce
    s.datagram(Drone().handshake(hello), DRONE)
    assert len(s.take()) == 1


def test_a_new_handshake_still_reads_the_last_sessions_datagrams() -> None:
    """DATA packed under the old key, on the way while the link re-authenticates,
    is still delivered; the config runs on (resumed)."""
    handler = Handler()
    s, clock, drone, sender = _running(handler)
    (old,) = sender.add_slot(0, 0.0, _slot(4.0)) + [sender.flush()]
    s.close("link down")
    handler.config = None
    drone2 = Drone()
    s.begin()
    s.datagram(drone2.handshake(s.take()[0]), DRONE)
    s.datagram(drone2.handshake(s.take()[0], 3), DRONE)
    assert s.datagram(old, DRONE) and handler.windows[0][0].value.number == 4.0
    assert s.radio.handshakes == 2


def test_silence_pings_then_ends_the_session() -> None:
    s, clock, drone, _ = _running(Handler())
    s.take()
    clock.advance(3.1)  # liveness 3 s (more than 2 x the 1 s accepted delay + 1)
    s.tick()
    assert [drone.read(d) for d in s.take()] == [Ping(b"alive")]
    clock.advance(1.0)
    s.tick()
    assert s.take() == []  # once per silence
    clock.advance(2.1)
    s.tick()
    assert [drone.read(d) for d in s.take()] == [Ping(b"alive")]
    clock.advance(2.9)  # three times the silence
    with pytest.raises(LinkDown, match="nothing from the PubBroker for 9.1 s"):
        s.tick()


def test_a_config_that_needs_no_more_than_the_packet_goes_whole() -> None:
    big = Config(4, 0, CONFIG.topics * 1, CONFIG.streams, accepted_delay_ms=2000)
    handler = Handler(config=None)
    s, clock, drone = _authenticated(handler, config_id=3)
    future = s.submit(big)
    (d,) = s.take()
    assert drone.read(d) == big
    s.datagram(drone.control(codec.encode(ConfigAck(4, 0, 5))), DRONE)
    assert future.result(timeout=0) == ConfigAck(4, 0, 5) and s.delay_s == 2.0


def test_an_overdue_datagram_is_asked_for_before_the_next_one_shows_the_gap() -> None:
    """The last datagram of a burst is lost: no later one opens a gap, so the session
    asks for the next slot once it is overdue (its date + the accepted delay + the
    learnt lateness + 0.25 s), at most five times, every ask interval."""
    handler = Handler()
    s, clock, drone, sender = _running(handler)
    (first,) = (
        sender.add_slot(0, 0.0, _slot(0.0))
        + sender.add_slot(1, 0.25, _slot(1.0))
        + sender.add_slot(2, 0.5, _slot(2.0))
    )
    lost = sender.flush()  # slot 2, lost on the radio
    clock.advance(0.3)  # slot 1's window ended 0.25 s after the epoch: 50 ms of lateness
    assert s.datagram(first, DRONE) and len(handler.windows) == 2
    clock.advance(1.0)  # slot 2 is dated 0.75 s; due 0.75 + 1 + 0.05 + 0.25 = 2.05 s
    s.tick()
    assert s.take() == [] and s.radio.nacks == 0
    asked: list[bytes] = []
    for _ in range(20):
        clock.advance(0.35)
        s.tick()
        asked += [d for n in s.take() for d in sender.on_control(n)]
    assert asked == [lost] * 5 and s.radio.nacks == 5  # MAX_NACK_ASKS
    s.datagram(lost, DRONE)
    assert [w.value.number for ws in handler.windows for w in ws] == [0.0, 1.0, 2.0]
    assert s.radio_status()["retransmissions"] == 1


def test_a_new_config_keeps_the_last_slots_of_the_one_it_replaces() -> None:
    """The replaced config's slots dated before the new epoch still come (packed
    before the switch) and are delivered; DATA of a config never acked is counted."""
    handler = Handler()
    s, clock, drone, sender = _running(handler)
    (late,) = sender.add_slot(0, 0.0, _slot(7.0)) + [sender.flush()]
    nxt = Config(4, 0, CONFIG.topics, CONFIG.streams)
    s.submit(nxt)
    s.datagram(drone.control(codec.encode(ConfigAck(4, 0, clock.wall_ns + 10**9))), DRONE)
    assert s.datagram(late, DRONE) and handler.windows[0][0].config_id == 3
    stray = DatagramSender(drone.key, 5, delay_s=1.0, room=10)
    (d,) = stray.add_slot(0, 0.0, _slot(1.0)) + [stray.flush()]
    assert not s.datagram(d, DRONE) and s.radio.unknown_config == 1
    assert sorted(s.runs.by_id) == [3, 4] and s.runs.by_id[3].end_ns == clock.wall_ns + 10**9


def test_a_link_with_nothing_to_say_pings_every_keepalive_period() -> None:
    """While DATA flows the base station sends nothing, but once every 30 s."""
    s, clock, drone, sender = _running(Handler())
    s.take()
    pings = 0
    for k in range(130):  # 65 s of a datagram of two slots every 0.5 s
        clock.advance(0.5)
        out = (
            sender.add_slot(2 * k, k * 0.5, _slot(1.0))
            + sender.add_slot(2 * k + 1, k * 0.5 + 0.25, _slot(1.0))
            + [sender.flush()]
        )
        for d in out:
            s.datagram(d, DRONE)
        s.tick()
        sent = [drone.read(d) for d in s.take()]
        assert all(m == Ping(b"alive") for m in sent), sent  # no NACK: nothing lost
        pings += len(sent)
    assert pings == 2


def test_the_radio_status_rates_over_the_last_ten_seconds() -> None:
    s, clock, drone, _ = _running(Handler())
    for k in range(60):  # 15 s: 100 B/s in, 10 B/s out on the wire
        s.sample_wire(k * 25, k * 2)
        clock.advance(0.25)
    status = s.radio_status(corrupt=3)
    assert status["wire_bytes_in_per_s"] == 100.0 and status["wire_bytes_out_per_s"] == 8.0
    assert status["malformed"] == 3 and status["transport"] == "udp"
    assert status["accepted_delay_s"] == 1.0 and status["pubbroker"] is None


def test_bytes_a_few_at_a_time_make_the_same_frames() -> None:
    """A stream cuts frames anywhere: the session reads the same handshake, DATA and
    backfill frames whether they come whole or byte by byte."""
    handler = Handler()
    s, clock = _session(handler)
    peer = PeerHandshake()
    s.begin()
    for b in peer.challenge(frames(s.take())[0]):
        s.feed(bytes([b]))
    for b in peer.auth_ok(frames(s.take())[0]):
        s.feed(bytes([b]))
    for _ in range(3):
        (ping,) = frames(s.take())
        assert isinstance(ping, Ping)
        s.feed(codec.encode(Pong(ping.payload)))
    s.take()
    wire = codec.encode(ConfigAck(3, 0, 0)) + _data(0, 1.0) + _data(1, 2.0)
    for i in range(0, len(wire), 3):
        s.feed(wire[i : i + 3])
    assert [w.value.number for (w,) in handler.windows] == [1.0, 2.0]
    assert handler.acked == [(CONFIG, ConfigAck(3, 0, 0))] and s.stats.data_frames == 2


def test_the_backlog_of_the_transport_counts_in_the_backpressure() -> None:
    clock = FakeClock()
    s = StreamSession(PSK, LinkOptions(), Handler(), lambda: 3.0, clock)
    s.backlog = lambda: 300_000
    _authenticate(s, clock, PeerHandshake())
    s.feed(codec.encode(ConfigAck(3, 0, 0)) + _data(0, 1.0))
    bp = s.stats.backpressure.as_dict()
    assert bp["recv_backlog_bytes"] == 300_000 and bp["behind"] is True


def test_a_malformed_status_is_read_as_far_as_it_goes_and_keeps_the_link() -> None:
    handler = Handler()
    s, clock = _session(handler)
    _authenticate(s, clock, PeerHandshake())
    # a name that is not UTF-8, a counter of 2^63 and a cut list: logged, left out
    body = codec.varint(2) + codec.varint(5) + codec.varint(1 << 63)
    body += codec.varint(2) + codec.varint(3) + b"\xff\xfe\xfd" + codec.varint(1) + codec.varint(1)
    body += codec.varint(4) + b"gnss" + codec.varint(5)  # cut here
    s.feed(codec.varint(len(body) + 1) + bytes([0x20]) + body)
    assert s.stats.pubbroker == {"uptime_s": 5}
    assert s.stats.sensors == {}
    s.feed(codec.encode(Status((6,), (SensorHealth("gnss", (1, 2)),))))  # the link goes on
    assert s.stats.pubbroker == {"uptime_s": 6}
    assert s.stats.sensors == {"gnss": {"state": 1, "lines_ok": 2}}
