"""Predicted bytes on the drone link, from the frame layout of the MoDD link
protocol (docs/protocol.md, section DATA; codec in runtime/python/src/modd/link/
codec.py and runtime/cpp) — keep :func:`data_frame_bytes` and
:func:`window_value_bytes` in step with that spec; they are cross-checked
against frames the real codec encodes.

DATA frame (the ordinary, non-sync form)::

    varint length | type (1 B) | slot sequence (1 B, slot mod 256)
    | presence bitmap (ceil(k/8) B, only when some stream is absent) | values

(the sync form, sent after a gap, carries config id + varint slot instead of
the sequence byte: rare, not counted.) Values in stream-id order, with the
wire type of :func:`aggregate_value_type`: float32 4 B, float64 8 B, int a
zigzag varint (estimated at :data:`INT_VALUE_BYTES`), bool 1 B; AVERAGE adds a
varint sample count; COUNT is a varint; ALL is a varint count then the raw
samples.
One TCP segment per slot: 52 B of IPv4 + TCP (timestamps option) headers,
and one pure ACK (52 B) per segment in the other direction.

The prediction assumes every stream present (a sample in every window).

The plain pub/sub comparison sends every raw sample to every subscriber as
its own MQTT 3.1.1 QoS 0 PUBLISH (2 B fixed header, 2 B topic length, the
full topic name, the raw value) in its own TCP segment, ACKed likewise.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from math import ceil, lcm

from modd_contracts import aggregations_gen as agg
from modd_contracts import events, labels
from modd_contracts.link_wire_gen import MAX_PERIOD_US
from modd_contracts.types_gen import PredictedLink

from .schedule import Schedule

TCP_IP_HEADER_BYTES = 52
UDP_IP_HEADER_BYTES = 28
DATA_HEADER_BYTES = 2  # type, slot sequence
INT_VALUE_BYTES = 4  # zigzag varint of a value below 2**27 in magnitude
SAMPLE_BYTES: dict[str, int] = {"float32": 4, "float64": 8, "int": INT_VALUE_BYTES, "bool": 1}
MQTT_PUBLISH_OVERHEAD_BYTES = 4  # fixed header + topic length
#: Above this many slots per hyperperiod the frame-length varints are
#: estimated from the mean frame instead of walked slot by slot.
EXACT_WALK_LIMIT = 20_000


def varint_size(n: int) -> int:
    """Bytes of an unsigned LEB128 varint.

    >>> varint_size(127), varint_size(128)
    (1, 2)
    """
    size = 1
    while n >= 0x80:
        n >>= 7
        size += 1
    return size


def aggregate_value_type(aggregation: str, topic_type: str) -> str:
    """Wire type of one aggregated value of a topic of ``topic_type``: the
    aggregation table's ``result``."""
    return labels.spec(aggregation).result[topic_type]


#: An event's value at most (an int topic's zigzag varint of 64 bits).
EVENT_VALUE_BYTES: dict[str, int] = {"float32": 4, "float64": 8, "int": 10, "bool": 1}


def events_at_most(aggregation: str, samples: Fraction) -> int:
    """An event stream's worst case, events a window: its declared N, else
    every sample of the window (at most the window's samples either way)."""
    n = events.parse_label(aggregation).max_events
    most = ceil(samples)
    return most if n is None else min(n, most)


def event_window_bytes(aggregation: str, topic_type: str, samples: Fraction, period_us: int) -> int:
    """Bytes of an event window at most (docs/protocol.md, "Event values"):
    the event count, each event's time (µs after the window's start) and
    value, and the coalesced count."""
    n = events_at_most(aggregation, samples)
    time_bytes = varint_size(max(period_us - 1, 0) if period_us else MAX_PERIOD_US)
    coalesced = varint_size(max(ceil(samples) - n, 0))
    return varint_size(n) + n * (time_bytes + EVENT_VALUE_BYTES[topic_type]) + coalesced


@lru_cache(maxsize=65_536)  # bounded: a long-running backend plans many models
def window_value_bytes(
    aggregation: str, topic_type: str, samples: Fraction, period_us: int = 0
) -> Fraction:
    """Expected bytes of one window's value when ``samples`` samples (on
    average) fall in a window; an event stream's at most (``period_us``, its
    window, sizes its events' times)."""
    if labels.is_event(aggregation):
        return Fraction(event_window_bytes(aggregation, topic_type, samples, period_us))
    count_bytes = varint_size(ceil(samples))
    if aggregation == agg.COUNT:
        return Fraction(count_bytes)
    value = SAMPLE_BYTES[aggregate_value_type(aggregation, topic_type)]
    if aggregation == agg.AVERAGE:
        return Fraction(value + count_bytes)
    if aggregation == agg.ALL:
        return count_bytes + samples * value
    if aggregation == agg.SUM and topic_type == "bool":  # zigzag varint of at most `samples`
        return Fraction(varint_size(2 * ceil(samples)))
    return Fraction(value)


def data_frame_bytes(values_bytes: int, stream_count: int, some_absent: bool = False) -> int:
    """Bytes of one DATA frame (length prefix included, no IP/TCP headers)."""
    body = DATA_HEADER_BYTES + values_bytes + ((stream_count + 7) // 8 if some_absent else 0)
    return varint_size(body) + body


@dataclass(frozen=True)
class LinkCost:
    """Predicted bytes per second, IP and TCP headers included."""

    drone_to_base: float
    base_to_drone: float
    plain_pubsub: float
    plain_pubsub_acks: float
    frames_per_s: float

    def to_json(self) -> PredictedLink:
        total = self.drone_to_base + self.base_to_drone
        plain = self.plain_pubsub + self.plain_pubsub_acks
        return {
            "drone_to_base": round(self.drone_to_base, 3),
            "base_to_drone": round(self.base_to_drone, 3),
            "plain_pubsub": round(self.plain_pubsub, 3),
            "plain_pubsub_acks": round(self.plain_pubsub_acks, 3),
            "frames_per_s": round(self.frames_per_s, 6),
            "saving_ratio": round(1 - total / plain, 6) if plain else 0.0,
        }


def _frame_bytes_per_hyperperiod(schedule: Schedule, window_bytes: Sequence[Fraction]) -> Fraction:
    """Sum of the DATA frames' sizes over one hyperperiod."""
    m = schedule.messages_per_hyperperiod
    if m == 0:
        return Fraction(0)
    if m <= EXACT_WALK_LIMIT:
        # equal window sizes are mostly the same object: count them, then
        # add each distinct one once per period (exact either way)
        same: dict[tuple[int, int], tuple[Fraction, int]] = {}
        for p, b in zip(schedule.periods_us, window_bytes, strict=True):
            b0, k = same.get((p, id(b)), (b, 0))
            same[(p, id(b))] = (b0, k + 1)
        per_period: dict[int, tuple[Fraction, int]] = {}
        for (p, _), (b, k) in same.items():
            total_b, count = per_period.get(p, (Fraction(0), 0))
            per_period[p] = (total_b + b * k, count + k)
        ceil_sum = ceil_of_sums({p: b for p, (b, _) in per_period.items()})
        counts = {p: k for p, (_, k) in per_period.items()}
        total = 0
        for index, _, due in schedule.iter_due_periods():
            if index == m:
                break
            total += data_frame_bytes(ceil_sum(due), sum(counts[p] for p in due))
        return Fraction(total)
    values = sum(
        (schedule.value_count_per_hyperperiod(i) * b for i, b in enumerate(window_bytes)),
        Fraction(0),
    )
    mean_body = DATA_HEADER_BYTES + values / m
    return values + m * (DATA_HEADER_BYTES + varint_size(ceil(mean_body)))


#: Bits of a common denominator up to which :func:`ceil_of_sums` adds integers.
_COMMON_DENOMINATOR_BITS = 512


def ceil_of_sums(values: Mapping[int, Fraction]) -> Callable[[Iterable[int]], int]:
    """``ceil(sum(values[k] for k in keys))`` as a function of ``keys``,
    exactly: on one common denominator the sum is of integers (a slot adds
    the bytes of its due periods: one Fraction addition each, with its gcd,
    was most of a long walk's time); Fractions when that denominator is huge."""
    den = lcm(*(v.denominator for v in values.values())) if values else 1
    if den.bit_length() > _COMMON_DENOMINATOR_BITS:
        return lambda keys: ceil(sum((values[k] for k in keys), Fraction(0)))
    scaled = {k: v.numerator * (den // v.denominator) for k, v in values.items()}
    return lambda keys: -(-sum(scaled[k] for k in keys) // den)


def predict(
    schedule: Schedule,
    window_bytes: Sequence[Fraction],
    plain_streams: Mapping[str, tuple[Fraction, int]],
) -> LinkCost:
    """Link cost of a schedule whose stream ``i`` carries ``window_bytes[i]``
    per window; ``plain_streams`` maps each subscriber to (publication period
    of its topic, bytes of one plain pub/sub message payload)."""
    m, h = schedule.messages_per_hyperperiod, schedule.hyperperiod
    # rates as exact ratios first: a hyperperiod may be far beyond a float
    frames = float(m / h) if m else 0.0
    data = float(_frame_bytes_per_hyperperiod(schedule, window_bytes) / h) if m else 0.0
    floats: dict[int, float] = {}  # float(pm) per period object (one per topic)
    for pm, _ in plain_streams.values():
        if id(pm) not in floats:
            floats[id(pm)] = float(pm)
    plain_rate = sum(1 / floats[id(pm)] for pm, _ in plain_streams.values())
    plain = sum(
        (TCP_IP_HEADER_BYTES + size) / floats[id(pm)] for pm, size in plain_streams.values()
    )
    return LinkCost(
        drone_to_base=data + frames * TCP_IP_HEADER_BYTES,
        base_to_drone=frames * TCP_IP_HEADER_BYTES,
        plain_pubsub=plain,
        plain_pubsub_acks=plain_rate * TCP_IP_HEADER_BYTES,
        frames_per_s=frames,
    )


def plain_message_bytes(topic: str, topic_type: str) -> int:
    """Payload of one plain pub/sub message carrying one raw sample."""
    return MQTT_PUBLISH_OVERHEAD_BYTES + len(topic.encode()) + SAMPLE_BYTES[topic_type]
