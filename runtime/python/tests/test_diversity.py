"""Diversity reception (docs/fleet.md): the serving station's datagram session takes
what another station's modem heard (forwarded through the mesh) as its own, on the
tag alone. The oracle is the slots the sender encoded: each arrives once, whichever
modem heard it first; a copy is neither delivered twice nor counted as a replay; a
forged one is refused; nothing is taken before the session has its key.
"""

from __future__ import annotations

import random
from typing import Any

import pytest
from modd.link import codec
from modd.link.datagram import (
    DGRAM_HANDSHAKE,
    DRONE_TO_BASE,
    DataDatagram,
    encode_control,
    encode_data,
    session_key,
)
from modd.link.frames import (
    Aggregation,
    Config,
    ConfigAck,
    Data,
    Pong,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
    value_kind,
)
from modd.link.receiver import Window
from modd.subbroker.config import LinkOptions
from modd.subbroker.dgsession import DatagramSession
from modd.subbroker.diversity import Bucket
from modd.subbroker.linkhooks import LinkDown

KEY = session_key(b"psk", bytes(16), bytes(range(16)))
KINDS = [value_kind(ValueType.FLOAT32, Aggregation.AVERAGE)]
CONFIG = Config(
    1,
    0,
    (TopicSpec("usv.t.x", ValueType.FLOAT32, 1),),
    (StreamSpec(0, Aggregation.AVERAGE, 250_000),),
)


class _Handler:
    def __init__(self) -> None:
        self.slots: list[int] = []

    def on_windows(self, windows: list[Window]) -> None:
        self.slots.append(windows[0].slot)

    def __getattr__(self, name: str) -> Any:
        return lambda *a, **k: None


def _session() -> tuple[DatagramSession, _Handler]:
    handler = _Handler()
    s = DatagramSession("udp", b"psk", LinkOptions(), handler)
    s._key = KEY  # an authenticated session (the handshake is not under test here)
    s.runs.accept(CONFIG, ConfigAck(1, 0, 10**18), KEY)
    return s, handler


def _datagram(slot: int) -> bytes:
    values = codec.encode_data(Data(False, 0, 0, 0, [Value(True, float(slot))]), KINDS)[3:]
    return encode_data(DataDatagram(1, slot, [values]), KEY, DRONE_TO_BASE)


def test_each_slot_once_whichever_modem_heard_it() -> None:
    """Two modems, 30 % loss each, drawn apart; the other's copies come forwarded,
    before or after this modem's own: the union arrives, each slot once."""
    s, handler = _session()
    rng = random.Random(44)
    heard_here = heard_there = 0
    expected = []
    for slot in range(400):
        raw = _datagram(slot)
        here, there = rng.random() > 0.3, rng.random() > 0.3
        heard_here += here
        heard_there += there
        if here or there:
            expected.append(slot)
        arrivals = [("own", raw)] * here + [("fwd", raw)] * there
        rng.shuffle(arrivals)  # the mesh may be faster than the own modem's read
        for how, d in arrivals:
            if how == "own":
                s.datagram(d, None)
            else:
                s.relayed(d)
    assert handler.slots == expected  # the union, in order, each once
    assert s.radio.replayed == 0, "a copy is not a replay"
    assert s.radio.heard_elsewhere == heard_there
    # what only the other modem heard, or heard first
    assert 0 < s.radio.heard_elsewhere_used < heard_there
    status = s.radio_status()
    assert status["heard_elsewhere"] == heard_there
    assert status["heard_elsewhere_used"] == s.radio.heard_elsewhere_used


def test_a_replay_on_this_modem_is_still_counted() -> None:
    s, handler = _session()
    raw = _datagram(5)
    assert s.datagram(raw, None)
    assert not s.datagram(raw, None)
    assert s.radio.replayed == 1 and handler.slots == [5]


def test_a_forged_forwarded_datagram_is_refused_and_counted() -> None:
    s, handler = _session()
    raw = bytearray(_datagram(3))
    raw[-1] ^= 1
    assert not s.relayed(bytes(raw))
    assert s.radio.forged == 1 and handler.slots == []


def test_nothing_is_taken_before_the_session_has_its_key_nor_a_handshake() -> None:
    handler = _Handler()
    s = DatagramSession("udp", b"psk", LinkOptions(), handler)
    assert not s.relayed(_datagram(1))
    s2, h2 = _session()
    assert not s2.relayed(bytes([DGRAM_HANDSHAKE, 1, 2, 3]))
    assert s.radio.heard_elsewhere == 0 and s2.radio.heard_elsewhere == 0
    assert handler.slots == h2.slots == []


def test_the_forwarding_bucket_bounds_a_flood() -> None:
    b = Bucket(per_s=200, now=0.0)
    sent = sum(b.take(t / 1000) for t in range(1000))  # 1,000 offered in one second
    assert 390 <= sent <= 410  # a second's depth, then 200 a second


class _Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def monotonic(self) -> float:
        return self.t

    def time_ns(self) -> int:
        return int(self.t * 1e9)


def _timed_session() -> tuple[DatagramSession, _Clock]:
    clock = _Clock()
    s = DatagramSession(
        "udp",
        b"psk",
        LinkOptions(),
        _Handler(),
        liveness_s=lambda: 3.0,
        clock=clock,
    )
    s._key = KEY
    s.runs.accept(CONFIG, ConfigAck(1, 0, 10**18), KEY)
    s._last_in = s._own_in = clock.t
    return s, clock


def _pong(counter: int) -> bytes:
    return encode_control(counter, codec.encode(Pong(b"alive")), KEY, DRONE_TO_BASE)


def test_a_station_the_drone_still_answers_keeps_the_link_on_forwarded_datagrams() -> None:
    """This station's modem hears nothing; the other's forwards the drone's data and
    its PONGs to this station's PINGs: the drone hears this station, the link stays."""
    s, clock = _timed_session()
    for k in range(1, 120):  # 60 s
        clock.t += 0.5
        s.relayed(_datagram(k))
        if k % 4 == 0:
            s.relayed(_pong(k))
        s.tick()  # raises LinkDown when the session is over
    assert s.take(), "this station PINGs while its own modem is silent"


def test_a_station_the_drone_no_longer_answers_gives_the_link_up() -> None:
    """The same without PONGs: the drone does not hear this station any more (its
    transmissions are lost): the link ends within three silences, and another station
    takes the drone over, rather than data arriving for minutes with no NACK answered."""
    s, clock = _timed_session()
    with pytest.raises(LinkDown, match="has not answered this station"):
        for k in range(1, 120):
            clock.t += 0.5
            s.relayed(_datagram(k))
            s.tick()
    assert clock.t - 1000.0 <= 3 * 3.0 + 1.0


class _ZenohStub:
    """What Diversity declares on its session (nothing crosses a network here)."""

    class _Entity:
        def put(self, raw: bytes) -> None: ...

        def undeclare(self) -> None: ...

    def declare_publisher(self, key: str) -> Any:
        return self._Entity()

    def declare_subscriber(self, key: str, callback: Any) -> Any:
        return self._Entity()


class _Port:
    """A datagram port whose next read gives ``queued`` (the drone is ``peer``)."""

    peer = ("127.0.0.1", 7171)

    def __init__(self) -> None:
        self.queued: list[tuple[bytes, Any]] = []
        self.wire_in = self.wire_out = 0

    def recv(self, timeout_s: float) -> list[tuple[bytes, Any]]:
        out, self.queued = self.queued, []
        return out


def _station() -> tuple[Any, Any, _Port]:
    from modd.subbroker.dglink import DatagramLinkClient
    from modd.subbroker.diversity import Diversity

    session = DatagramSession("udp", b"psk", LinkOptions(), _Handler(), peer=_Port.peer)
    port = _Port()
    link = DatagramLinkClient(lambda: port, session, LinkOptions())  # type: ignore[arg-type,return-value]
    link._port = port  # type: ignore[assignment]
    diversity = Diversity(_ZenohStub(), "usv", "b", link)  # type: ignore[arg-type]
    return link, diversity, port


def test_what_a_station_heard_is_kept_for_a_takeover_within_its_bound() -> None:
    """Kept: what the modem heard standing by (DATA only), what the session could not read
    before it was up (a takeover's handshake), what another station forwarded meanwhile;
    at most HEARD_KEPT datagrams, the newest; read once."""
    from modd.subbroker import diversity as div

    link, diversity, port = _station()
    diversity.forward(_datagram(1))
    diversity.forward(encode_control(1, codec.encode(Pong(b"x")), KEY, DRONE_TO_BASE))  # control
    port.queued = [(_datagram(2), _Port.peer), (_datagram(3), ("127.0.0.9", 1))]  # a stranger
    link._read()  # the session is not up: it cannot read them
    sample = type("S", (), {"key_expr": "modd/usv/fleet/heard/c"})()
    sample.payload = type("P", (), {"to_bytes": lambda self: _datagram(4)})()
    diversity._on_heard(sample)
    assert diversity.take_heard() == [_datagram(1), _datagram(2), _datagram(4)]
    assert diversity.take_heard() == []
    for k in range(div.HEARD_KEPT + 10):
        diversity.forward(_datagram(k))
    kept = diversity.take_heard()
    assert len(kept) == div.HEARD_KEPT and kept[-1] == _datagram(div.HEARD_KEPT + 9)
    assert kept[0] == _datagram(10)


def test_a_session_that_is_up_keeps_nothing() -> None:
    link, diversity, port = _station()
    link.dgram._up.set()
    port.queued = [(_datagram(2), _Port.peer)]
    link._read()
    assert diversity.take_heard() == []
