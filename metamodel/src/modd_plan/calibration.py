"""Quantised value sizes measured on an archive of real data (docs/planning.md,
"Bounds and estimates"): a test flight's samples, per topic, turned into the
windows each sent stream would carry and coded as the link codec codes them
(docs/protocol.md, "Quantised values"), give the mean bytes of a stream's
first value in a unit (absolute) and of the others (deltas). The planner
sizes quantised values with them instead of the declared range
(resolution.py): an estimate for the signal the scientists measure.

Pure: the samples come in as ``{topic: (stamps_ns, values)}``; reading an
archive is the runtime's (the ``modd.samples`` entry point, cli.py).

>>> cal = Calibration("test.mcap", {"t": ([0, 10**9, 2 * 10**9], [0.0, 0.05, 9.0])})
>>> cal.sizes("t", "LAST", Fraction(1), 0.01)
ValueSizes(absolute=Fraction(1, 1), delta=Fraction(1, 1), windows=2)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from modd_contracts import aggregations_gen as agg
from modd_contracts.quantised import ESCAPE, steps
from modd_contracts.types_gen import PlanCalibration

from .derive import aggregate
from .linkcost import varint_size

#: Windows of each stream recomputed at most (the first ones of the archive):
#: bounds the work of a calibration (each plan and proposal reuses it); 2,000
#: windows are 8 minutes of a 0.25 s stream, far more for slower ones.
CALIBRATION_WINDOWS = 2000
#: Samples of each topic an archive reader hands over at most (the first ones,
#: in time order): bounds the memory and the reading of a long mission's
#: archive (a reader stops once every topic has as many); 200,000 samples are
#: 2.2 hours at 25 Hz, and 2,000 windows of a 1 s stream at 100 Hz.
SAMPLES_LIMIT = 200_000
#: An escaped value: code 0, then the exact f64le.
ESCAPE_BYTES = varint_size(ESCAPE) + 8
#: Mean sizes are kept as fractions of at most this denominator.
MEAN_DENOMINATOR = 100
_NS = 1_000_000_000

#: One topic's samples: stamps (ns, ascending) and values.
Series = tuple[Sequence[int], Sequence[float]]


class CalibrationError(ValueError):
    """An archive that cannot calibrate a plan (unreadable, corrupt, or
    without the model's topics); the message names the file and the place."""


@dataclass(frozen=True)
class ValueSizes:
    """Mean bytes of one quantised value of a stream: its first in a unit
    (absolute steps) and a later one (a delta against the previous)."""

    absolute: Fraction
    delta: Fraction
    windows: int


def code_bytes(q: int | None, prev: int | None) -> int:
    """Bytes of one value's code: ``varint(zigzag(q - prev) + 1)``, absolute
    when ``prev`` is None, the escape when ``q`` is None.

    >>> code_bytes(123, None), code_bytes(125, 123), code_bytes(None, 1)
    (2, 1, 9)
    """
    if q is None:
        return ESCAPE_BYTES
    d = q - prev if prev is not None else q
    return varint_size((2 * d if d >= 0 else -2 * d - 1) + 1)


def window_numbers(
    series: Series, aggregation: str, period: Fraction, limit: int
) -> list[list[float]]:
    """The float values each present window of a stream carries, in order,
    over the first ``limit`` windows of the series: one per window, each
    element for ALL (none for COUNT: it is not quantised). Windows start at
    the first sample (the PubBroker's epoch is not in the archive: the
    phase changes which samples share a window, not their statistics); the
    window the archive ends in is cut short and left out (unless it is the
    only one), as its AVERAGE or MIN of a part of the signal is not the
    stream's."""
    stamps, values = series
    if not len(stamps) or aggregation == agg.COUNT:
        return []
    period_ns = int(period * _NS)  # whole microseconds: exact
    first = int(stamps[0])
    out: list[list[float]] = []
    index: int | None = None
    samples: list[float] = []
    for t, x in zip(stamps, values, strict=True):
        j = (int(t) - first) // period_ns
        if j >= limit:
            break
        if j != index and samples:
            out.append(_numbers(aggregation, samples))
            samples = []
        index = j
        samples.append(float(x))
    else:  # the archive ends inside this window: it is cut short, left out
        samples = samples if not out else []
    if samples:
        out.append(_numbers(aggregation, samples))
    return out


def _numbers(aggregation: str, samples: list[float]) -> list[float]:
    value: Any = aggregate(aggregation, samples)
    if aggregation == agg.ALL:
        return list(value)
    if aggregation == agg.AVERAGE:
        return [value[0]]
    return [float(value)]


def value_sizes(windows: Sequence[Sequence[float]], resolution: float) -> ValueSizes | None:
    """Mean bytes of an absolute value (each window's first, coded as the
    first of a unit) and of a delta (every other value, against the previous
    one of the stream: the next window's first too); None with no window."""
    absolute: list[int] = []
    deltas: list[int] = []
    prev: int | None = None  # the chain: an escaped value does not move it
    for numbers in windows:
        for k, x in enumerate(numbers):
            q = steps(x, resolution)
            if k == 0:
                absolute.append(code_bytes(q, None))
            if k > 0 or prev is not None:
                deltas.append(code_bytes(q, prev))
            prev = q if q is not None else prev
    if not absolute:
        return None
    # means to 1/100 B: small denominators keep the plan's exact sums cheap
    mean_abs = Fraction(sum(absolute), len(absolute)).limit_denominator(MEAN_DENOMINATOR)
    mean_delta = (
        Fraction(sum(deltas), len(deltas)).limit_denominator(MEAN_DENOMINATOR)
        if deltas
        else mean_abs
    )
    return ValueSizes(mean_abs, mean_delta, len(windows))


@dataclass(frozen=True)
class CalibrationUse:
    """What a calibration gave a plan: each quantised stream's measured sizes
    (by stream key), and the quantised streams its archive has no sample of
    (sized as without a calibration)."""

    source: str
    limit: int
    sizes: tuple[tuple[str, ValueSizes], ...]
    missing: tuple[str, ...]

    def to_json(self) -> PlanCalibration:
        """The plan JSON's ``radio.calibration`` (docs/planning.md)."""
        return {
            "windows_limit": self.limit,
            "streams": [
                {
                    "stream": key,
                    "absolute_bytes": round(float(v.absolute), 3),
                    "delta_bytes": round(float(v.delta), 3),
                    "windows": v.windows,
                }
                for key, v in self.sizes
            ],
            "not_calibrated": list(self.missing),
        }


@dataclass(frozen=True)
class Calibration:
    """An archive's samples, by topic, and the sizes measured on them (each
    stream's computed once, on first use: proposals re-plan with the same)."""

    source: str
    series: Mapping[str, Series]
    limit: int = CALIBRATION_WINDOWS
    _cache: dict[tuple[str, str, Fraction, float], ValueSizes | None] = field(
        default_factory=dict, repr=False, compare=False
    )

    def sizes(
        self, topic: str, aggregation: str, period: Fraction, resolution: float
    ) -> ValueSizes | None:
        """The mean sizes of a stream's quantised values; None when the
        archive holds no sample of its topic."""
        key = (topic, aggregation, period, resolution)
        if key not in self._cache:
            series = self.series.get(topic)
            windows = window_numbers(series, aggregation, period, self.limit) if series else []
            self._cache[key] = value_sizes(windows, resolution)
        return self._cache[key]
