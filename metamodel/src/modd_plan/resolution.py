"""The resolution each sent stream goes with (docs/planning.md, "Declared
resolution"): the finest of what the subscriptions it serves need, directly or
through the streams derived from it; None (unquantised) as soon as one of them
needs full precision. A subscription needs its own ``resolution``, else its
variable's. A SUM source of k windows is sent k times finer, so that the sum of
k errors of half a step stays within half of the subscriber's step; a RANGE
derived from ALL asks it twice finer (a difference of two samples). The other
derivations (MIN, MAX, an AVERAGE of AVERAGEs or of ALL samples, a MEDIAN or
STDDEV of ALL's samples) keep the error of their sources; an ALL stream a SUM is
derived from is sent exact (no resolution).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from fractions import Fraction
from math import ceil, floor
from typing import Any

from modd_contracts import aggregations_gen as agg
from modd_model.query import Topic, topic_name

from .calibration import Calibration, CalibrationUse, ValueSizes
from .linkcost import SAMPLE_BYTES, aggregate_value_type, varint_size
from .streams import PlannedStream

#: Bytes of a delta between consecutive windows (|delta| <= 63 steps): the
#: planner's estimate assumes a signal that moves less than 64 steps a window
#: (its bound, the declared range's width: plan.py, radio.py).
DELTA_BYTES = 1
#: Step count assumed for a stream's first value in a datagram when its
#: variable declares no validMin/validMax: 2^20 steps (3 bytes).
UNBOUNDED_STEPS = 1 << 20


def needed(model: Mapping[str, Any]) -> dict[str, float | None]:
    """Each subscriber's resolution: its own, else its variable's, else None."""
    drone = model["drone"]["name"]
    declared = {
        topic_name(drone, s["name"], v["name"]): v.get("resolution")
        for s in model["drone"]["sensors"]
        for v in s["variables"]
    }
    return {
        sub["name"]: sub.get("resolution", declared.get(sub["topic"]))
        for sub in model.get("subscribers", [])
    }


def stream_resolutions(
    model: Mapping[str, Any], sent: Sequence[PlannedStream], streams: Sequence[PlannedStream]
) -> list[float | None]:
    """One resolution per sent stream, in ``sent``'s order."""
    need = needed(model)
    # by identity, as plan._budget: a derived stream's sources hold its source's key
    asks: dict[int, list[float | None]] = {
        id(s.stream): [need.get(n) for n in s.subscribers] for s in sent
    }
    for s in streams:
        if s.id is not None:
            continue
        for src in s.sources:
            into = asks.get(id(src.stream))
            if into is None:
                continue
            divide = src.factor if src.stream.aggregation == agg.SUM else 1
            if s.stream.aggregation == agg.RANGE:  # a difference of two quantised samples
                divide *= 2
            # A SUM of an ALL stream adds as many errors as there are samples, a count no
            # CONFIG bounds: its samples go exact (an AVERAGE of them keeps half a step).
            exact = s.stream.aggregation == agg.SUM and src.stream.aggregation == agg.ALL
            into += [
                None if exact or need.get(n) is None else need[n] / divide  # type: ignore[operator]
                for n in s.subscribers
            ]
    return [
        None
        if not asks[id(s.stream)] or None in asks[id(s.stream)]
        else min(r for r in asks[id(s.stream)] if r is not None)
        for s in sent
    ]


def _value_bytes(model: Mapping[str, Any], topic: str, resolution: float) -> tuple[int, int] | None:
    """Bytes of an absolute value and of a delta at the variable's declared
    validMin/validMax (the largest step count, the range's width in steps);
    None when it declares no range."""
    drone = model["drone"]["name"]
    for s in model["drone"]["sensors"]:
        for v in s["variables"]:
            if topic_name(drone, s["name"], v["name"]) == topic:
                lo, hi = v.get("validMin"), v.get("validMax")
                if not (isinstance(lo, int | float) and isinstance(hi, int | float)):
                    return None
                steps = ceil(max(abs(lo), abs(hi)) / resolution)
                width = ceil(abs(hi - lo) / resolution)
                return varint_size(2 * steps + 1), varint_size(2 * width + 1)
    return None


def quantised_streams(
    model: Mapping[str, Any],
    sent: Sequence[PlannedStream],
    streams: Sequence[PlannedStream],
    tops: Mapping[str, Topic],
) -> Iterator[tuple[int, PlannedStream, float, str]]:
    """The sent streams whose values go as steps: (index in ``sent``, the
    stream, its resolution, its value's wire type); COUNT and int or bool
    values are exact already."""
    for i, (s, r) in enumerate(zip(sent, stream_resolutions(model, sent, streams), strict=True)):
        topic = tops.get(s.stream.topic)
        if r is None or topic is None:
            continue
        wire = aggregate_value_type(s.stream.aggregation, topic.type)
        if s.stream.aggregation == agg.COUNT or wire not in ("float32", "float64"):
            continue
        yield i, s, r, wire


def calibration_use(
    model: Mapping[str, Any],
    sent: Sequence[PlannedStream],
    streams: Sequence[PlannedStream],
    tops: Mapping[str, Topic],
    calibration: Calibration,
) -> CalibrationUse:
    """The sizes ``calibration`` gives the plan's quantised streams."""
    sizes: list[tuple[str, ValueSizes]] = []
    missing: list[str] = []
    for _, s, r, _ in quantised_streams(model, sent, streams, tops):
        k = s.stream
        got = calibration.sizes(k.topic, k.aggregation, k.period, r)
        if got is None:
            missing.append(k.key)
        else:
            sizes.append((k.key, got))
    return CalibrationUse(calibration.source, calibration.limit, tuple(sizes), tuple(missing))


def quantised_window_bytes(
    model: Mapping[str, Any],
    sent: Sequence[PlannedStream],
    streams: Sequence[PlannedStream],
    exact: Sequence[Fraction],
    tops: Mapping[str, Topic],
    transport: str,
    accepted_delay: Fraction,
    deltas_at_range: bool = False,
    calibration: Calibration | None = None,
) -> tuple[list[Fraction], bool | None]:
    """``exact`` (bytes of one window's value per sent stream) with the float
    values of streams that have a resolution counted as steps: one absolute
    value per datagram (per DATA frame over tcp), sized at the declared range,
    deltas of DELTA_BYTES else (at the range's width with ``deltas_at_range``);
    both at their mean sizes measured by ``calibration`` when its archive has
    the stream's topic (calibration.py). And what the sizes are: True, upper
    bounds (every quantised value sized at its declared range: a signal inside
    it never costs more), False, an estimate (deltas assumed small, a variable
    without a range, or calibrated sizes), None, exact (nothing quantised)."""
    out = list(exact)
    bound: bool | None = None
    for i, s, r, wire in quantised_streams(model, sent, streams, tops):
        k = s.stream
        measured = calibration.sizes(k.topic, k.aggregation, k.period, r) if calibration else None
        ranged = _value_bytes(model, k.topic, r)
        key: Fraction | int = ranged[0] if ranged else varint_size(2 * UNBOUNDED_STEPS + 1)
        delta: Fraction | int = ranged[1] if ranged and deltas_at_range else DELTA_BYTES
        # keys per window: one a datagram, which holds the windows of the accepted
        # delay and one more (its first slot waits at most the delay)
        per_datagram = 1 if transport == "tcp" else floor(accepted_delay / k.period) + 1
        only_keys = per_datagram == 1 and k.aggregation != agg.ALL
        bound = bound is not False and ranged is not None and (only_keys or deltas_at_range)
        if measured is not None:
            key, delta = measured.absolute, measured.delta
            bound = False
        share = Fraction(1, per_datagram)
        if k.aggregation == agg.ALL:
            samples = (exact[i] - 1) / SAMPLE_BYTES[wire]  # the count's varint, roughly 1 B
            out[i] = exact[i] - samples * (SAMPLE_BYTES[wire] - delta) + (key - delta) * share
        else:
            out[i] = exact[i] - SAMPLE_BYTES[wire] + delta + (key - delta) * share
    return out, bound
