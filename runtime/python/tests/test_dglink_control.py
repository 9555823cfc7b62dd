"""A control datagram from the PubBroker may carry several link frames: a backfill's
PROGRESS rides with the DATA or END it reports on (one datagram, one header, one tag).
The SubBroker's datagram link hands every one of them on, in order; before, it read the
first and dropped the rest, so over udp and serial a backfill's END never arrived and
its job stayed RUNNING (found by tests/bench/bench_backfill.py --live)."""

from __future__ import annotations

from modd.link import backfill as bf
from modd.link import codec
from modd.link.datagram import DRONE_TO_BASE, encode_control, session_key
from modd.subbroker.dglink import DatagramLinkClient, control_frames

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
