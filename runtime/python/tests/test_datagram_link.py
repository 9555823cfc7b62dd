"""The datagram link's protocol end to end in simulated time: the sender packs
scenario 1's slots (4 AVERAGE/MIN/MAX float32 streams every 0.25 s) up to the
accepted delay, an emulated radio (modd.radio.channel: loss, jitter, a 30 s
outage) carries them, the receiver verifies, decodes and NACKs; the oracle is
the values the sender encoded. Simulated time keeps the 30 s outage fast."""

from __future__ import annotations

import heapq

from modd.link import codec
from modd.link.datagram import session_key
from modd.link.dgreceiver import DatagramReceiver, DatagramSender
from modd.link.frames import Aggregation, Data, Value, ValueType, value_kind
from modd.radio.channel import Channel, RadioSpec

KINDS = [
    value_kind(ValueType.FLOAT32, a)
    for a in (Aggregation.AVERAGE, Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX)
]
PERIODS = [250_000] * 4
KEY = session_key(b"psk", bytes(16), bytes(range(16)))


def _values(slot: int) -> list[Value]:
    return [
        Value(True, float(slot % 1000), 0, 6),
        Value(True, -1.0, 0, 7),
        Value(True, float(slot % 97)),
        Value(True, 2.5),
    ]


def _encoded(slot: int) -> bytes:
    return codec.encode_data(Data(False, 0, 0, 0, _values(slot)), KINDS)[3:]


def _run(
    spec: RadioSpec, seconds: float, forge: bool = False
) -> tuple[dict[int, list[Value]], DatagramReceiver, Channel, Channel]:
    sender = DatagramSender(KEY, 1, delay_s=1.0, room=1400)
    receiver = DatagramReceiver(KEY, 1, PERIODS, KINDS)
    down, up = Channel(spec, 1), Channel(spec, 2)
    events: list[tuple[float, int, str, bytes]] = []
    n = 0
    got: dict[int, list[Value]] = {}

    def push(at: float | None, kind: str, raw: bytes) -> None:
        nonlocal n
        if at is not None:
            n += 1
            heapq.heappush(events, (at, n, kind, raw))

    slots = int(seconds / 0.25)
    for k in range(slots):
        now = (k + 1) * 0.25
        while events and events[0][0] <= now:
            t, _, kind, raw = heapq.heappop(events)
            if kind == "base":
                for slot, vals in receiver.on_datagram(raw, t):
                    got[slot] = vals
            else:
                for d in sender.on_control(raw):
                    push(down.offer(d, t), "base", d)
        for d in sender.add_slot(k, now, _encoded(k)) + sender.due(now):
            push(down.offer(d, now), "base", d)
            if forge:
                bad = bytearray(d)
                bad[6] ^= 0x40
                push(now + 0.01, "base", bytes(bad))
                push(now + 0.02, "base", d)  # replayed as is
        nack = receiver.nack(now, every=1.0)
        if nack is not None:
            push(up.offer(nack, now), "drone", nack)
    return got, receiver, down, up


def test_no_loss_every_slot_and_nothing_back() -> None:
    got, receiver, down, up = _run(RadioSpec(rate=3600, latency_ms=80), 120)
    assert set(got) >= set(range(0, 470))
    assert all(
        got[k][0].number == float(k % 1000) and got[k][2].number == float(k % 97) for k in got
    )
    assert receiver.stats.nacks == 0 and up.passed == 0  # nothing flows back
    # drone->base bytes as the planner predicts: 0.8 datagrams/s of 98 B (+28 IP/UDP)
    assert abs(down.passed_bytes / 120 - 0.8 * 98) < 2


def test_loss_jitter_is_repaired() -> None:
    for loss, target in ((0.05, 0.999), (0.20, 0.99)):
        got, receiver, down, _ = _run(
            RadioSpec(rate=3600, loss=loss, latency_ms=80, jitter_ms=60, seed=4), 250
        )
        expected = set(range(0, 980))
        share = len(set(got) & expected) / len(expected)
        assert share >= target, (loss, share, receiver.gaps.lost)
        assert receiver.stats.nacks > 0


def test_thirty_second_outage_is_reported_and_the_link_resumes() -> None:
    spec = RadioSpec(rate=3600, latency_ms=80, outages=((20.0, 30.0),), seed=1)
    got, receiver, down, _ = _run(spec, 120)
    assert down.dropped["outage"] > 0
    # the resend ring (256 datagrams, about 5 min of scenario 1) outlives the outage:
    # once the radio is back, the NACKs bring every slot of the 30 s
    assert set(range(0, 470)) <= set(got)
    assert receiver.stats.nacks > 0 and receiver.gaps.lost == 0


def test_outage_longer_than_the_ring_loses_only_the_live_view() -> None:
    spec = RadioSpec(rate=3600, latency_ms=80, outages=((20.0, 400.0),), seed=1)
    got, receiver, _, _ = _run(spec, 480)
    missing = set(range(0, 1870)) - set(got)
    assert missing and set(range(1700, 1870)) <= set(got)  # resumes after it
    assert receiver.gaps.lost + receiver.gaps.missing >= len(missing)  # counted, not guessed


def test_forged_and_replayed_datagrams_are_counted_never_decoded() -> None:
    got, receiver, _, _ = _run(RadioSpec(latency_ms=10), 30, forge=True)
    assert receiver.stats.forged > 20 and receiver.stats.replayed > 20
    assert all(got[k][0].number == float(k % 1000) for k in got)  # only genuine values


def test_a_new_session_key_refuses_the_old_sessions_datagrams() -> None:
    sender = DatagramSender(KEY, 1, delay_s=1.0, room=1400)
    old = sender.add_slot(0, 0.25, _encoded(0)) + [sender.flush()]
    rebooted = DatagramReceiver(session_key(b"psk", bytes(16), bytes(16)), 1, PERIODS, KINDS)
    assert rebooted.on_datagram(old[0], 1.0) == [] and rebooted.stats.forged == 1


def test_control_datagram_with_several_frames_delivers_each() -> None:
    """The PubBroker writes a backfill's PROGRESS and END in one write, so one
    CONTROL datagram may hold several frames: each reaches the backfill sink,
    and a truncated tail is refused as malformed."""
    from modd.link import backfill as bf
    from modd.link.datagram import DRONE_TO_BASE, encode_control
    from modd.subbroker.config import LinkOptions
    from modd.subbroker.dgsession import DatagramSession

    client = DatagramSession("udp", b"psk", LinkOptions(), None)  # type: ignore[arg-type]
    key = session_key(b"psk", bytes(16), bytes(16))
    client._key = key
    got: list[codec.RawFrame] = []
    client.backfill_sink = got.append
    frames = bf.encode(bf.BackfillProgress(7, 24, 24, 96, 20000)) + bf.encode(
        bf.BackfillEnd(7, bf.EndStatus.DONE, 24, "")
    )
    assert client.datagram(encode_control(1, frames, key, DRONE_TO_BASE))
    assert [f.type for f in got] == [bf.BackfillType.PROGRESS, bf.BackfillType.END]
    assert not client.datagram(encode_control(2, frames[:-1], key, DRONE_TO_BASE))
    assert client.radio.malformed == 1 and len(got) == 2
