"""A control datagram from the PubBroker may carry several link frames: a backfill's
PROGRESS rides with the DATA or END it reports on (one datagram, one header, one tag).
The SubBroker's datagram link hands every one of them on, in order; before, it read the
first and dropped the rest, so over udp and serial a backfill's END never arrived and
its job stayed RUNNING (found by tests/bench/bench_backfill.py --live)."""

from __future__ import annotations

from modd.link import backfill as bf
from modd.link import codec
from modd.link.datagram import DRONE_TO_BASE, encode_control, session_key
from modd.link.frames import Aggregation, Config, ErrorCode, StreamSpec, TopicSpec, ValueType
from modd.subbroker.config import LinkOptions
from modd.subbroker.dglink import DatagramLinkClient, control_frames
from modd.subbroker.link import ConfigRejected

KEY = session_key(b"psk", bytes(16), bytes(range(16)))


def _end_with_progress() -> bytes:
    return (bf.encode(bf.BackfillProgress(7, 55, 55, 309, 499))
            + bf.encode(bf.BackfillEnd(7, bf.EndStatus.DONE, 55)))


def test_control_frames_splits_every_frame_in_order() -> None:
    frames = control_frames(_end_with_progress())
    assert frames is not None
    assert [bf.decode(f) for f in frames] == [bf.BackfillProgress(7, 55, 55, 309, 499),
                                              bf.BackfillEnd(7, bf.EndStatus.DONE, 55)]
    one = bf.encode(bf.BackfillEnd(7, bf.EndStatus.DONE, 55))
    assert [f.type for f in control_frames(one) or []] == [codec.split_frame(one).type]  # type: ignore[union-attr]


def test_control_frames_refuses_a_torn_or_empty_payload() -> None:
    whole = _end_with_progress()
    assert control_frames(whole[:-1]) is None  # the END cut short
    assert control_frames(b"") is None
    assert control_frames(bytes([0])) is None  # a frame length of 0


def test_the_datagram_link_hands_on_the_end_behind_a_progress() -> None:
    client = DatagramLinkClient(lambda: None, "test", "udp", b"psk", None, None)  # type: ignore[arg-type,return-value]
    client._key = KEY  # an authenticated session (the handshake is not under test here)
    got: list[object] = []
    client.backfill_sink = lambda f: got.append(bf.decode(f))
    assert client._on_datagram(encode_control(1, _end_with_progress(), KEY, DRONE_TO_BASE))
    assert got == [bf.BackfillProgress(7, 55, 55, 309, 499),
                   bf.BackfillEnd(7, bf.EndStatus.DONE, 55)]
    assert client.stats.frames_in == 2
    # a torn payload is malformed, nothing of it handed on
    assert not client._on_datagram(encode_control(2, _end_with_progress()[:-1], KEY, DRONE_TO_BASE))
    assert client.radio.malformed == 1 and len(got) == 2


def _config(topics: int) -> Config:
    names = tuple(TopicSpec(f"usv.sensor.topic_{i:03d}", ValueType.FLOAT32, 1)
                  for i in range(topics))
    streams = tuple(StreamSpec(i, Aggregation.AVERAGE, 250_000) for i in range(topics))
    return Config(3, 0, names, streams)


def test_a_config_larger_than_the_radios_packet_is_refused_with_its_sizes() -> None:
    """Control datagrams are not cut: a CONFIG that does not fit one packet used to be
    sent and lost on the radio every time, the deploy ending in "no CONFIG_ACK"."""
    sent: list[bytes] = []

    class Port:
        def send(self, datagram: bytes) -> None:
            sent.append(datagram)

    def client(max_packet: int) -> DatagramLinkClient:
        c = DatagramLinkClient(lambda: Port(), "serial /dev/radio", "serial", b"psk",  # type: ignore[arg-type,return-value]
                               LinkOptions(), None, max_packet=max_packet)  # type: ignore[arg-type]
        c._key, c._port = KEY, Port()  # type: ignore[assignment]
        return c

    big = _config(20)
    refused = client(252)._submit(big)
    exc = refused.exception(timeout=0)
    assert isinstance(exc, ConfigRejected) and exc.status == ErrorCode.BAD_CONFIG
    assert "config 3 is" in str(exc) and "link.maxPacket 252 B" in str(exc), exc
    assert sent == []  # nothing sent that the radio would drop
    size = int(str(exc).split(" is ")[1].split(" B")[0])
    assert size == len(encode_control(1 << 32, codec.encode(big), KEY, DRONE_TO_BASE))
    # the same config on a radio whose packet holds it goes out
    client(1024)._submit(big)
    assert len(sent) == 1 and len(sent[0]) <= size
