"""The wide form (``--resample PERIOD``): one row per period, one column per
topic holding the mean of its samples in that period (NaN when it had none),
the position interpolated to the period's centre, which is the row's time.
Periods are aligned on the Unix epoch (multiples of PERIOD), so two exports
of the same archive line up. Memory: one row per period with samples.

>>> r = Resampler(1.0, lambda plan, table, summary: None)
>>> r.add("t", np.array([0, 400_000_000, 1_200_000_000]), np.array([1.0, 3.0, 5.0]))
>>> [(int(b), s, n) for b, (s, n) in sorted(r.sums["t"].items())]
[(0, 4.0, 2), (1, 5.0, 1)]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .export import Summary
from .plan import ExportPlan, Variable
from .position import Track


@dataclass
class WideTable:
    period_s: float
    time_ns: np.ndarray  # the periods' centres
    columns: dict[str, np.ndarray]  # by topic: float64 means
    lat: np.ndarray
    lon: np.ndarray
    alt: np.ndarray
    #: Received windows (``--received``) only: 1 where a backfilled (historical) window
    #: went into the period's mean, else 0; None for the archive's samples.
    historical: np.ndarray | None = None


WideWriter = Callable[[ExportPlan, WideTable, Summary], None]


class Resampler:
    """A sink that bins samples per period, then hands the table to a writer."""

    takes_qc = False  # a period's mean has no QARTOD flag (docs: "Quality flags")

    def __init__(self, period_s: float, writer: WideWriter) -> None:
        if not period_s > 0:
            raise ValueError("the resampling period must be greater than zero")
        self.period_s = period_s
        self.period_ns = int(round(period_s * 1e9))
        self.writer = writer
        self.sums: dict[str, dict[int, tuple[float, int]]] = {}
        self.track: Track | None = None
        #: The periods holding a backfilled window; None unless the windows are received ones.
        self.marked: set[int] | None = None

    def open(self, plan: ExportPlan, track: Track | None) -> None:
        self.track = track
        self.sums = {t: {} for t in plan.variables}
        self.marked = set() if plan.source == "received" else None

    def add(self, topic: str, time_ns: np.ndarray, value: np.ndarray) -> None:
        bins = time_ns // self.period_ns
        keys, inverse = np.unique(bins, return_inverse=True)
        v = value.astype(np.float64)
        sums = np.bincount(inverse, weights=v, minlength=len(keys))
        counts = np.bincount(inverse, minlength=len(keys))
        acc = self.sums.setdefault(topic, {})
        for k, s, n in zip(keys.tolist(), sums.tolist(), counts.tolist(), strict=True):
            old = acc.get(k, (0.0, 0))
            acc[k] = (old[0] + s, old[1] + n)

    def write(
        self,
        var: Variable,
        time_ns: np.ndarray,
        value: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        other: np.ndarray | None = None,
        qc: np.ndarray | None = None,
        historical: np.ndarray | None = None,
        location: np.ndarray | None = None,
    ) -> None:
        self.add(var.topic, time_ns, value)  # a period has the axis's time only
        if self.marked is not None and historical is not None:
            self.marked.update((time_ns[historical.astype(bool)] // self.period_ns).tolist())

    def table(self) -> WideTable:
        keys = np.array(sorted({k for acc in self.sums.values() for k in acc}), dtype=np.int64)
        index = {k: i for i, k in enumerate(keys.tolist())}
        columns = {}
        for topic, acc in self.sums.items():
            col = np.full(len(keys), np.nan)
            for k, (s, n) in acc.items():
                col[index[k]] = s / n
            columns[topic] = col
        centre = keys * self.period_ns + self.period_ns // 2
        if self.track is not None:
            lat, lon, alt = self.track.at(centre)
        else:
            lat = lon = alt = np.full(len(keys), np.nan)
        marks = None
        if self.marked is not None:
            marks = np.isin(keys, np.fromiter(self.marked, np.int64)).astype(np.uint8)
        return WideTable(self.period_s, centre, columns, lat, lon, alt, marks)

    def close(self, plan: ExportPlan, summary: Summary) -> None:
        self.writer(plan, self.table(), summary)
