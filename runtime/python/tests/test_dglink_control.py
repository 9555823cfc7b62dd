"""A control datagram from the PubBroker may carry several link frames: a backfill's
PROGRESS rides with the DATA or END it reports on (one datagram, one header, one tag).
The SubBroker's datagram link hands every one of them on, in order; before, it read the
first and dropped the rest, so over udp and serial a backfill's END never arrived and
its job stayed RUNNING (found by tests/bench/bench_backfill.py --live)."""

from __future__ import annotations

from concurrent.futures import Future

from modd.link import backfill as bf
from modd.link import codec
from modd.link.datagram import (
    BASE_TO_DRONE,
    DRONE_TO_BASE,
    ControlPieces,
    encode_control,
    encode_control_fragments,
    session_key,
    verify_control_fragment,
)
from modd.link.frames import (
    Aggregation,
    Config,
    ConfigAck,
    ErrorCode,
    StreamSpec,
    TopicSpec,
    ValueType,
)
from modd.subbroker.config import LinkOptions
from modd.subbroker.dglink import control_frames
from modd.subbroker.dgsession import DatagramSession
from modd.subbroker.link import ConfigRejected
from modd_plan.linkbudget import datagram_capacity

KEY = session_key(b"psk", bytes(16), bytes(range(16)))


def _end_with_progress() -> bytes:
    return bf.encode(bf.BackfillProgress(7, 55, 55, 309, 499)) + bf.encode(
        bf.BackfillEnd(7, bf.EndStatus.DONE, 55)
    )


def test_control_frames_splits_every_frame_in_order() -> None:
    frames = control_frames(_end_with_progress())
    assert frames is not None
    assert [bf.decode(f) for f in frames] == [
        bf.BackfillProgress(7, 55, 55, 309, 499),
        bf.BackfillEnd(7, bf.EndStatus.DONE, 55),
    ]
    one = bf.encode(bf.BackfillEnd(7, bf.EndStatus.DONE, 55))
    assert [f.type for f in control_frames(one) or []] == [codec.split_frame(one).type]  # type: ignore[union-attr]


def test_control_frames_refuses_a_torn_or_empty_payload() -> None:
    whole = _end_with_progress()
    assert control_frames(whole[:-1]) is None  # the END cut short
    assert control_frames(b"") is None
    assert control_frames(bytes([0])) is None  # a frame length of 0


def test_the_datagram_link_hands_on_the_end_behind_a_progress() -> None:
    client = DatagramSession("udp", b"psk", LinkOptions(), None)  # type: ignore[arg-type]
    client._key = KEY  # an authenticated session (the handshake is not under test here)
    got: list[object] = []
    client.backfill_sink = lambda f: got.append(bf.decode(f))
    assert client.datagram(encode_control(1, _end_with_progress(), KEY, DRONE_TO_BASE))
    assert got == [
        bf.BackfillProgress(7, 55, 55, 309, 499),
        bf.BackfillEnd(7, bf.EndStatus.DONE, 55),
    ]
    assert client.stats.frames_in == 2
    # a torn payload is malformed, nothing of it handed on
    assert not client.datagram(encode_control(2, _end_with_progress()[:-1], KEY, DRONE_TO_BASE))
    assert client.radio.malformed == 1 and len(got) == 2


def _config(topics: int) -> Config:
    names = tuple(
        TopicSpec(f"usv.sensor.topic_{i:03d}", ValueType.FLOAT32, 1) for i in range(topics)
    )
    streams = tuple(StreamSpec(i, Aggregation.AVERAGE, 250_000) for i in range(topics))
    return Config(3, 0, names, streams)


class _Port:
    """What the session emits, as its pump writes it."""

    def __init__(self) -> None:
        self.sent: list[bytes] = []


class _Client(DatagramSession):
    def __init__(self, max_packet: int, port: _Port) -> None:
        super().__init__(
            "serial",
            b"psk",
            LinkOptions(),
            None,  # type: ignore[arg-type]
            max_packet=max_packet,
            where="serial /dev/radio",
        )
        self._key, self._port = KEY, port
        self._counter = 41

    def _submit(self, config: Config) -> Future[ConfigAck]:
        future = self.submit(config)
        self._port.sent.extend(self.take())
        return future


def _client(max_packet: int, port: _Port) -> _Client:
    return _Client(max_packet, port)


def test_a_config_larger_than_the_radios_packet_goes_as_control_fragments() -> None:
    """A CONFIG that does not fit one packet (scenario 2's is 517 B in its control
    datagram, a SiK radio carries 248 B) goes as control fragments under
    consecutive counters, each within the packet; the pieces put back together
    are the CONFIG frame (the PubBroker's side: test_dgram_link.cpp)."""
    port = _Port()
    big = _config(20)
    frame = codec.encode(big)
    assert len(encode_control(1, frame, KEY, BASE_TO_DRONE)) > datagram_capacity("serial", 252)
    _client(252, port)._submit(big)
    assert len(port.sent) == 3
    assert all(len(d) <= datagram_capacity("serial", 252) for d in port.sent)
    pieces = [verify_control_fragment(d, KEY, BASE_TO_DRONE) for d in port.sent]
    assert [p.counter for p in pieces] == [42, 43, 44]
    assert [(p.index, p.count, p.first) for p in pieces] == [(0, 3, 42), (1, 3, 42), (2, 3, 42)]
    whole = ControlPieces()
    assert [whole.add(p) for p in reversed(pieces)][-1] == frame  # in any order
    # a CONFIG that fits one packet is one CONTROL datagram, as before
    port.sent.clear()
    _client(1024, port)._submit(big)
    assert len(port.sent) == 1 and port.sent[0][0] == 0x40


def test_a_config_beyond_sixteen_fragments_is_refused_with_its_sizes() -> None:
    """Sixteen fragments at most: a larger CONFIG is refused at the deploy, with
    its size and the packet's, instead of being lost on the radio at every try."""
    port = _Port()
    big = _config(200)
    refused = _client(252, port)._submit(big)
    exc = refused.exception(timeout=0)
    assert isinstance(exc, ConfigRejected) and exc.status == ErrorCode.BAD_CONFIG
    assert f"config 3 is {len(codec.encode(big))} B" in str(exc), exc
    assert "link.maxPacket 252 B" in str(exc) and "16 control fragments" in str(exc), exc
    assert port.sent == []  # nothing sent that the PubBroker could not put back together


def test_control_fragments_from_the_pubbroker_are_put_back_together() -> None:
    """The SubBroker reads control fragments too (drone to base): a forged piece
    is counted and dropped, a replayed one too, and the message is handled once
    its pieces are all there, in any order."""
    port = _Port()
    client = _client(252, port)
    message = _end_with_progress() * 30  # ~ 600 B of backfill frames
    got: list[int] = []
    client.backfill_sink = lambda f: got.append(f.type)
    frags = encode_control_fragments(7, message, 100, KEY, DRONE_TO_BASE)
    assert len(frags) > 3
    forged = frags[1][:-1] + bytes([frags[1][-1] ^ 1])
    assert not client.datagram(forged) and client.radio.forged == 1
    for d in reversed(frags):
        assert client.datagram(d)
    assert not client.datagram(frags[0]) and client.radio.replayed == 1
    assert len(got) == 60  # every frame of the message, once
