"""Derived streams: which aggregation can be computed from which, and the pure
merge functions that compute it.

A *window* is the value one stream carries for one of its periods. Its Python
form depends on the aggregation (``None`` means the window had no sample, the
link's presence bitmap marks it absent):

===========  ==================================================
MIN MAX      the extreme sample, or ``None``
FIRST LAST   the first / last sample, or ``None``
SUM          the sum of the samples (``0`` for an empty window)
COUNT        the number of samples (``int``)
AVERAGE      ``(mean, count)``, or ``None`` when ``count == 0``
ALL          the list of raw samples, in publication order
MEDIAN       numpy.median of the samples (float), or ``None``
STDDEV       the population standard deviation (numpy.std, ddof=0), or ``None``
RANGE        MAX - MIN, or ``None``
PERCENTILE   numpy.percentile(samples, p) (linear), or ``None``; the
             aggregation is named by its label, ``PERCENTILE(95)``
===========  ==================================================

MEDIAN, STDDEV, RANGE and PERCENTILE(p) are exact over their window and cannot be merged
(the aggregation table derives them from ALL only).

A stream of period ``k·P`` is derived from ``k`` consecutive windows of a sent
stream of period ``P``. Every window starts at the configuration epoch, so the
``k`` source windows tile the derived window exactly. The SubBroker calls
:func:`derive_value` with the windows in time order.

>>> merge("MIN", [3.0, None, 1.5])
1.5
>>> merge("AVERAGE", [(2.0, 2), (5.0, 1)])
(3.0, 3)
>>> derive_value("COUNT", [("AVERAGE", [(2.0, 2), None])])
2
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from typing import Any

from modd_contracts import aggregations_gen as agg
from modd_contracts.aggregations_gen import AGGREGATIONS
from modd_contracts.labels import ByLabel, parse

Sample = float | int | bool
Window = Any

#: For each aggregation, the aggregations of ONE sent stream it can be derived
#: from, most preferred first (same aggregation, then cheaper, ALL last): the
#: aggregation table's ``derivableFrom`` (metamodel/modd.schema.json).
SINGLE_SOURCE_RULES: dict[str, tuple[str, ...]] = ByLabel(
    {a.name: a.derivable_from for a in AGGREGATIONS}
)

#: Aggregations derivable from TWO sent streams together (AVERAGE = SUM / COUNT):
#: the table's ``derivableFromPair``.
PAIR_SOURCE_RULES: dict[str, tuple[str, str]] = ByLabel(
    {a.name: a.derivable_from_pair for a in AGGREGATIONS if a.derivable_from_pair}
)


def _present(windows: Sequence[Window]) -> list[Window]:
    return [w for w in windows if w is not None]


def merge_min(windows: Sequence[Sample | None]) -> Sample | None:
    """Smallest of the present windows; ``None`` when all are absent."""
    present = _present(windows)
    return min(present) if present else None


def merge_max(windows: Sequence[Sample | None]) -> Sample | None:
    """Largest of the present windows; ``None`` when all are absent."""
    present = _present(windows)
    return max(present) if present else None


def merge_first(windows: Sequence[Sample | None]) -> Sample | None:
    """First present window (windows are in time order)."""
    present = _present(windows)
    return present[0] if present else None


def merge_last(windows: Sequence[Sample | None]) -> Sample | None:
    """Last present window (windows are in time order)."""
    present = _present(windows)
    return present[-1] if present else None


def exact_sum(values: Iterable[Sample]) -> Sample:
    """The sum with no precision lost: ints (and bools) exactly, floats correctly
    rounded once (``math.fsum``, then exact fractions when an intermediate sum
    overflows); a sum beyond the double range is ``±inf``, ``inf − inf`` is ``nan``.

    >>> exact_sum([3.4e38, -9.0e13, -3.4e38]), sum([3.4e38, -9.0e13, -3.4e38])
    (-90000000000000.0, 0.0)
    >>> exact_sum([1e308, 1e308, -1e308]), exact_sum([1e308, 1e308]), exact_sum([2, True])
    (1e+308, inf, 3)
    """
    xs = list(values)
    if not any(isinstance(x, float) for x in xs):
        return sum(xs, 0)
    try:
        return math.fsum(xs)
    except ValueError:  # inf and -inf among the values
        return math.nan
    except OverflowError:
        if not all(math.isfinite(x) for x in xs):
            return math.fsum(x for x in xs if not math.isfinite(x))
        total = sum((Fraction(x) for x in xs), Fraction(0))
        try:
            return float(total)
        except OverflowError:
            return math.inf if total > 0 else -math.inf


def merge_sum(windows: Sequence[Sample | None]) -> Sample:
    """Sum of the window sums (absent windows count as 0)."""
    return exact_sum(w for w in windows if w is not None)


def merge_count(windows: Sequence[int | None]) -> int:
    """Total number of samples."""
    return sum(w for w in windows if w is not None)


def merge_average(windows: Sequence[tuple[float, int] | None]) -> tuple[float, int] | None:
    """Count-weighted mean of the window means: exact up to float rounding,
    as the window counts travel with the means."""
    present = [w for w in windows if w is not None and w[1] > 0]
    count = sum(c for _, c in present)
    if count == 0:
        return None
    return (exact_sum(m * c for m, c in present) / count, count)


def merge_all(windows: Sequence[Sequence[Sample] | None]) -> list[Sample]:
    """Concatenation of the raw samples."""
    out: list[Sample] = []
    for w in windows:
        if w is not None:
            out.extend(w)
    return out


MERGES: dict[str, Callable[[Sequence[Any]], Any]] = {
    agg.MIN: merge_min,
    agg.MAX: merge_max,
    agg.FIRST: merge_first,
    agg.LAST: merge_last,
    agg.SUM: merge_sum,
    agg.COUNT: merge_count,
    agg.AVERAGE: merge_average,
    agg.ALL: merge_all,
}


def merge(aggregation: str, windows: Sequence[Window]) -> Window:
    """Combine consecutive windows of one aggregation into one window."""
    return MERGES[aggregation](windows)


def aggregate(aggregation: str, samples: Sequence[Sample]) -> Window:
    """The window value of ``aggregation`` over raw ``samples`` (what the
    PubBroker computes; also how anything is derived from ALL).

    >>> aggregate("AVERAGE", [1.0, 2.0, 6.0])
    (3.0, 3)
    """
    if aggregation == agg.ALL:
        return list(samples)
    if aggregation == agg.COUNT:
        return len(samples)
    if aggregation == agg.SUM:
        return exact_sum(samples)
    if aggregation == agg.AVERAGE:
        return (exact_sum(samples) / len(samples), len(samples)) if samples else None
    whole = _WHOLE.get(aggregation)
    if whole is None and aggregation.startswith(agg.PERCENTILE):
        p = parse(aggregation)[1]
        assert p is not None
        return percentile(samples, p) if samples else None
    if whole is None:
        raise ValueError(f"unknown aggregation {aggregation!r}")
    return whole(samples) if samples else None


def median(samples: Sequence[Sample]) -> float:
    """numpy.median: the middle sample, or the mean of the two middle ones.

    >>> median([3, 1, 2]), median([4.0, 1.0, 2.0, 3.0])
    (2.0, 2.5)
    """
    s = sorted(samples)
    mid = len(s) // 2
    return float(s[mid]) if len(s) % 2 else (float(s[mid - 1]) + float(s[mid])) / 2


def stddev(samples: Sequence[Sample]) -> float:
    """The population standard deviation (numpy.std with ddof=0), two passes.

    >>> stddev([2, 4, 4, 4, 5, 5, 7, 9])
    2.0
    """
    mean = math.fsum(float(x) for x in samples) / len(samples)
    return math.sqrt(math.fsum((float(x) - mean) ** 2 for x in samples) / len(samples))


def percentile(samples: Sequence[Sample], p: float) -> float:
    """numpy.percentile(samples, p) with its default ``method="linear"``: the
    sorted samples' value at the virtual index ``(n - 1) * p / 100``, between
    its two neighbours as numpy interpolates them (from the upper one when the
    fraction is at least a half), so that the result is numpy's to the bit.

    >>> percentile([1, 2, 3, 4], 50), percentile([10.0, 0.0, 5.0], 95), percentile([7], 0.1)
    (2.5, 9.5, 7.0)
    """
    if not 0 <= p <= 100:
        raise ValueError(f"percentile {p!r} is not in [0, 100]")
    s = sorted(float(x) for x in samples)
    index = (len(s) - 1) * (p / 100)
    lower = math.floor(index)
    if lower >= len(s) - 1:
        return s[-1]
    a, b, t = s[lower], s[lower + 1], index - lower
    return b - (b - a) * (1 - t) if t >= 0.5 else a + (b - a) * t


#: The aggregations computed from a non-empty window's samples as a whole.
_WHOLE: dict[str, Callable[[Sequence[Sample]], Window]] = {
    agg.MIN: min,
    agg.MAX: max,
    agg.FIRST: lambda s: s[0],
    agg.LAST: lambda s: s[-1],
    agg.MEDIAN: median,
    agg.STDDEV: stddev,
    agg.RANGE: lambda s: max(s) - min(s),
}


def _convert(target: str, source: str, window: Window) -> Window:
    """One source window seen as a window of ``target`` (same time span)."""
    if source == target:
        return window
    if source == agg.ALL:
        return aggregate(target, window or [])
    if target == agg.COUNT and source == agg.AVERAGE:
        return 0 if window is None else window[1]
    raise ValueError(f"{target} cannot be derived from {source}")


def derive_value(target: str, sources: Sequence[tuple[str, Sequence[Window]]]) -> Window:
    """The value of a derived stream from the windows of its sources.

    ``sources`` lists ``(source aggregation, windows in time order)``; one
    source for the single-source rules, ``SUM`` then ``COUNT`` for the pair
    rule. Raises ValueError when no rule applies.
    """
    if len(sources) == 1:
        source, windows = sources[0]
        if target not in MERGES and source != agg.ALL:  # exact over the whole window: from ALL only
            raise ValueError(f"{target} cannot be derived from {source}")
        if source == agg.ALL:  # every sample at once: one rounding, not one per window
            return aggregate(target, merge_all(windows))
        return merge(target, [_convert(target, source, w) for w in windows])
    if len(sources) == 2 and PAIR_SOURCE_RULES.get(target) == (sources[0][0], sources[1][0]):
        total = merge_sum(sources[0][1])
        count = merge_count(sources[1][1])
        return (float(total) / count, count) if count else None
    raise ValueError(f"{target} cannot be derived from {[s for s, _ in sources]}")
