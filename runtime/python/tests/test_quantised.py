"""Declared resolution on the live link (docs/protocol.md, "Quantised values"):
the shared vectors (contracts/vectors/link/quantised.json), the error bound for any
value (Hypothesis), and loss: datagrams of quantised slots through the emulated
radio at 5 % loss (with NACK repair, and with none), every delivered value
within half a step of what the sender aggregated."""

from __future__ import annotations

import heapq
import json
import math
import random
import struct
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from modd.link import codec
from modd.link.codec import get_number, put_number
from modd.link.datagram import session_key
from modd.link.dgreceiver import DatagramReceiver, DatagramSender
from modd.link.frames import Aggregation, ProtocolError, Value, ValueType, value_kind
from modd.link.quantise import MAX_STEPS, steps
from modd.radio.channel import Channel, RadioSpec
from modd_plan.derive import derive_value

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "link"
STEP = 0.01
KINDS = [
    value_kind(ValueType.FLOAT32, a, STEP)
    for a in (Aggregation.AVERAGE, Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX)
]
PERIODS = [250_000] * 4
KEY = session_key(b"psk", bytes(16), bytes(range(16)))


def test_vectors_decode_and_encode_byte_for_byte() -> None:
    doc = json.loads((VECTORS / "quantised.json").read_text())
    assert len(doc["units"]) >= 3
    for unit in doc["units"]:
        kinds = [
            value_kind(
                ValueType.parse(k["type"]), Aggregation[k["aggregation"]], k.get("resolution")
            )
            for k in unit["kinds"]
        ]
        wire = bytes.fromhex(unit["hex"])
        r, chain = codec.Reader(wire), dict[int, int]()
        for slot in unit["slots"]:
            for s, want in zip(slot["streams"], slot["values"], strict=True):
                if not want["present"]:
                    continue
                got = codec._get_value(r, kinds[s], chain, s)
                assert (got.number, got.count, got.samples) == (
                    want["number"],
                    want["count"],
                    want["samples"],
                ), unit["name"]
                sent = want["sent"] if isinstance(want["sent"], list) else [want["sent"]]
                back = got.samples or [got.number]
                for x, y in zip(sent, back, strict=True):  # the bound, or an exact escape
                    assert abs(x - y) <= kinds[s].resolution / 2 or abs(x - y) <= abs(x) * 1e-7
        r.end()
        chain = {}
        again = b"".join(
            codec.encode_slot_values(
                [
                    Value(v["present"], v["number"], 0, v["count"], v["samples"])
                    for v in slot["values"]
                ],
                [kinds[s] for s in slot["streams"]],
                slot["streams"],
                chain,
            )
            for slot in unit["slots"]
        )
        assert again == wire, unit["name"]


finite = st.floats(allow_nan=False, allow_infinity=False)
resolutions = st.sampled_from([1e-9, 0.001, 0.01, 0.05, 0.1, 1.0, 7.3, 1e6])


@settings(max_examples=400, deadline=None)
@given(st.lists(finite, min_size=1, max_size=20), resolutions)
def test_every_value_comes_back_within_half_a_step(xs: list[float], r: float) -> None:
    b, chain = bytearray(), dict[int, int]()
    for x in xs:
        put_number(b, chain, 3, x, r)
    rd, back = codec.Reader(bytes(b)), dict[int, int]()
    for x in xs:
        y = get_number(rd, back, 3, r)
        assert abs(y - x) <= r / 2 or y == x  # quantised, or escaped exactly
    rd.end()


@pytest.mark.parametrize("x", [math.inf, -math.inf, math.nan, 1e300, -(2.0**60)])
def test_values_beyond_the_steps_escape_exactly(x: float) -> None:
    assert steps(x, 0.01) is None
    b = bytearray()
    put_number(b, {}, 0, x, 0.01)
    assert b[0] == 0 and len(b) == 9
    y = get_number(codec.Reader(bytes(b)), {}, 0, 0.01)
    assert y == x or (math.isnan(x) and math.isnan(y))


def test_a_delta_beyond_the_steps_is_a_located_bad_frame() -> None:
    big = codec.varint(codec.zigzag(MAX_STEPS) + 1)  # absolute 2^53: the limit, accepted
    get_number(codec.Reader(big), {}, 0, 1.0)
    with pytest.raises(ProtocolError, match="beyond 2\\^53"):
        get_number(codec.Reader(big), {0: 1}, 0, 1.0)
    with pytest.raises(ProtocolError, match="beyond 2\\^54"):
        get_number(codec.Reader(codec.varint((1 << 64) - 1)), {}, 0, 1.0)


def _walk(seed: int, n: int) -> list[list[Value]]:
    """Scenario 1's slots from a random walk (AVERAGE x, y with counts, MIN and MAX z)."""
    rng = random.Random(seed)
    x = y = z = 0.0
    out = []
    for _ in range(n):
        x, y, z = x + rng.gauss(0, 0.05), y + rng.gauss(0, 0.05), z + rng.gauss(0, 0.2)
        f32 = [struct.unpack("<f", struct.pack("<f", v))[0] for v in (x, y, z, z + 0.3)]
        out.append(
            [
                Value(True, f32[0], 0, 6),
                Value(True, f32[1], 0, 7),
                Value(True, f32[2]),
                Value(True, f32[3]),
            ]
        )
    return out


def _run(spec: RadioSpec, seconds: float, nack: bool) -> tuple[dict[int, list[Value]], int]:
    slots = _walk(7, int(seconds / 0.25))
    sender = DatagramSender(KEY, 1, delay_s=1.0, room=1400)
    receiver = DatagramReceiver(KEY, 1, PERIODS, KINDS)
    down, up = Channel(spec, 1), Channel(spec, 2)
    events: list[tuple[float, int, str, bytes]] = []
    got: dict[int, list[Value]] = {}
    sent_bytes = 0

    def push(at: float | None, kind: str, raw: bytes) -> None:
        if at is not None:
            heapq.heappush(events, (at, len(events) + sum(map(len, got.values())), kind, raw))

    for k, vals in enumerate(slots):
        now = (k + 1) * 0.25
        while events and events[0][0] <= now:
            t, _, kind, raw = heapq.heappop(events)
            if kind == "base":
                got.update(receiver.on_datagram(raw, t))
            else:
                for d in sender.on_control(raw):
                    push(down.offer(d, t), "base", d)

        def enc(chain: dict[int, int], vals: list[Value] = vals) -> bytes:
            return codec.encode_slot_values(vals, KINDS, range(4), chain)

        for d in sender.add_values(k, now, enc) + sender.due(now):
            sent_bytes += len(d)
            push(down.offer(d, now), "base", d)
        ask = receiver.nack(now, every=1.0) if nack else None
        if ask is not None:
            push(up.offer(ask, now), "drone", ask)
    for k, vals in got.items():
        for want, have in zip(slots[k], vals, strict=True):
            assert abs(have.number - want.number) <= STEP / 2, (k, want.number, have.number)
            assert have.count == want.count
    return got, sent_bytes


def test_a_lost_datagram_leaves_later_values_within_half_a_step() -> None:
    got, _ = _run(RadioSpec(rate=3600, loss=0.05, latency_ms=80, seed=3), 200, nack=False)
    missing = set(range(790)) - set(got)
    assert missing and len(got) > 700  # datagrams were lost, the later ones decoded exactly


def test_at_5_percent_loss_every_window_arrives_within_half_a_step() -> None:
    got, sent = _run(
        RadioSpec(rate=3600, loss=0.05, latency_ms=80, jitter_ms=60, seed=4), 250, nack=True
    )
    assert set(range(980)) <= set(got)
    lossless, plain = _run(RadioSpec(rate=3600, latency_ms=80), 100, nack=False)
    assert plain / 100 < 50  # datagrams of 5 quantised slots: about 46 B against 98 B


def test_a_config_with_resolutions_round_trips_and_names_them_by_stream() -> None:
    from modd.link.frames import Config, StreamSpec, TopicSpec

    topics = (TopicSpec("d.s.v", ValueType.FLOAT32, 1),)
    streams = tuple(
        StreamSpec(0, a, 250_000) for a in (Aggregation.MIN, Aggregation.COUNT, Aggregation.MAX)
    )
    c = Config(1, 0, topics, streams, 1000, (0.5, None, 0.25))
    (raw,) = codec.FrameSplitter().feed(codec.encode(c))
    back = codec.decode(raw)
    assert back == c
    assert [k.resolution for k in c.kinds()] == [0.5, None, 0.25]
    with pytest.raises(ValueError, match="accepted delay"):
        codec.encode(Config(1, 0, topics, streams, None, (0.5, None, 0.25)))


def test_a_refused_config_with_resolutions_says_an_older_pubbroker_may_be_why() -> None:
    from modd.link.frames import Config, StreamSpec, TopicSpec
    from modd.subbroker.broker import _older_peer

    topics = (TopicSpec("d.s.v", ValueType.FLOAT32, 1),)
    streams = (StreamSpec(0, Aggregation.MIN, 250_000),)
    assert _older_peer(Config(1, 0, topics, streams)) == ""
    hint = _older_peer(Config(1, 0, topics, streams, 1000, (0.01,)))
    assert "declares resolutions" in hint and "update the PubBroker" in hint


# -- derivations from ALL (docs/protocol.md, "Quantised values") --------------------------
f32_samples = st.floats(width=32, allow_nan=False, allow_infinity=False)
FLT_MAX = 3.4028234663852886e38


def _through_the_link(windows: list[list[float]], r: float) -> list[list[float]]:
    """Each window's ALL elements written and read by the codec at resolution r."""
    out = []
    for w in windows:
        b, chain = bytearray(), dict[int, int]()
        for x in w:
            put_number(b, chain, 0, x, r)
        rd, back = codec.Reader(bytes(b)), dict[int, int]()
        out.append([get_number(rd, back, 0, r) for _ in w])
    return out


def _within_half_a_step(got: float, exact_sum: Fraction, n: int, r: float) -> bool:
    """|got − exact_sum / n| ≤ r/2, up to the two roundings of a double mean (the sum's,
    shared by n, and the division's): they matter only where r is below a double's ulp."""
    slack = Fraction(math.ulp(float(exact_sum))) / n + Fraction(math.ulp(got))
    return abs(Fraction(got) - exact_sum / n) <= Fraction(r) / 2 + slack


@settings(max_examples=300, deadline=None)
@given(st.lists(st.lists(f32_samples, max_size=12), min_size=1, max_size=8), resolutions)
def test_sum_and_average_derived_from_all_stay_within_half_a_step(
    windows: list[list[float]], r: float
) -> None:
    exact = sum((Fraction(x) for w in windows for x in w), Fraction(0))
    n = sum(len(w) for w in windows)
    # the SUM's ALL source goes exact (modd_plan.resolution): the sum is rounded once
    assert derive_value("SUM", [("ALL", windows)]) == float(exact)
    # the AVERAGE's ALL source goes quantised: a mean of values each within half a step
    got = derive_value("AVERAGE", [("ALL", _through_the_link(windows, r))])
    if n == 0:
        assert got is None
    else:
        assert got[1] == n and _within_half_a_step(got[0], exact, n, r)


def test_a_window_with_plus_and_minus_flt_max_keeps_its_small_sum() -> None:
    windows = [[FLT_MAX, -4.5e13], [-4.5e13, -FLT_MAX]]
    assert sum(x for w in windows for x in w) == 0.0  # the naive sum
    assert derive_value("SUM", [("ALL", windows)]) == -9.0e13
    assert derive_value("AVERAGE", [("ALL", windows)]) == (-2.25e13, 4)


def test_a_sum_of_all_samples_is_sent_exact_while_an_average_keeps_its_steps() -> None:
    from modd_plan.resolution import stream_resolutions  # noqa: PLC0415
    from modd_plan.streams import PlannedStream, Source, StreamKey  # noqa: PLC0415

    topic = "usv.ctd.t"
    src = StreamKey(topic, "ALL", Fraction(1, 4))
    sent = [PlannedStream(src, 0, (), ("s_all",))]
    model = {
        "drone": {
            "name": "usv",
            "sensors": [{"name": "ctd", "variables": [{"name": "t", "resolution": 0.01}]}],
        },
        "subscribers": [{"name": n, "topic": topic} for n in ("s_all", "s_sum", "s_ave")],
    }
    for agg, want in (("SUM", None), ("AVERAGE", 0.01)):
        key = StreamKey(topic, agg, Fraction(2))
        derived = PlannedStream(key, None, (Source(src, 8),), (f"s_{agg.lower()[:3]}",))
        assert stream_resolutions(model, sent, [*sent, derived]) == [want]
