"""QARTOD quality flags through the community's library, ``ioos_qc``
(docs/user-guide/datasets.md, "Quality flags").

Per topic, the tests a ``qc`` section of the dataset metadata file names
(keyed by topic, then by ``ioos_qc`` test name, then its parameters), and by
default a gross range test from the model's declared valid range (``validMin``
/ ``validMax``: outside it FAIL). Each batch of a topic is flagged as the
export reads it (one batch: at most ``export.BATCH`` samples) with the last
``TAIL`` samples of the topic's previous batch before it as context, so
memory stays bounded; the aggregate flag is ``ioos_qc.qartod.qartod_compare``
of the tests' flags (1 PASS, 2 NOT_EVALUATED, 3 SUSPECT, 4 FAIL, 9 MISSING).
Every sample's position (the track interpolated to its time) gets the location
test's flag when the model declares a position (``location_flags``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .plan import ExportPlan, PlanError, Variable
from .qcconfig import POSITION, QcConfig
from .qcfast import (
    fast_test,
    location_bounds_test,
    location_test,
    median_step,
    qartod_compare,
)

#: Samples of a topic's previous batch kept as context for the next (spike, rate of
#: change and flat line look back; a flat line longer than this is cut at a batch's start).
TAIL = 4096
#: The aggregate flag's CF attributes (IOOS 1.2, QARTOD).
FLAG_ATTRS: dict[str, Any] = {
    "flag_values": np.array([1, 2, 3, 4, 9], dtype=np.int8),
    "flag_meanings": "PASS NOT_EVALUATED SUSPECT FAIL MISSING",
    "standard_name": "aggregate_quality_flag",
    "coverage_content_type": "qualityInformation",
}


def _defaults(var: Variable) -> dict[str, dict[str, Any]]:
    if var.valid_min is None or var.valid_max is None:
        return {}
    return {"gross_range_test": {"fail_span": [var.valid_min, var.valid_max]}}


def qc_config(plan: ExportPlan) -> QcConfig:
    """The tests of each exported topic (the model's range, then the file's tests);
    a topic of the file that the model does not have is a PlanError."""
    given = plan.metadata.qc
    known = plan.model_topics or tuple(plan.variables)
    unknown = [t for t in given if t not in known and t != POSITION]  # --topics: no error
    if unknown:
        source = plan.metadata.source or "dataset metadata"
        raise PlanError(f"{source}: qc.{unknown[0]}: not a topic of the model ({', '.join(known)})")
    if POSITION in given and plan.position is None:
        source = plan.metadata.source or "dataset metadata"
        raise PlanError(f"{source}: qc.{POSITION}: the model declares no position")
    out: QcConfig = {}
    if plan.source == "received":  # a window's aggregate (a count, a spread) is no sample
        return out
    for topic, var in plan.variables.items():
        if var.value_type == "bool":
            continue
        tests = _defaults(var) | given.get(topic, {})
        if tests:
            out[topic] = tests
    return out


def location_config(plan: ExportPlan) -> dict[str, Any] | None:
    """The location test's parameters (``qc.position.location_test``): it runs whenever
    the model declares a position (an impossible position needs no configuration), on
    every sample's position; None without a position, or for received windows."""
    if plan.position is None or plan.source == "received":
        return None
    params: dict[str, Any] = plan.metadata.qc.get(POSITION, {}).get("location_test", {})
    return params


def location_flags(params: dict[str, Any], lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    """The aggregate of ``ioos_qc``'s ``location_test`` (impossible positions) and, with
    a ``bbox``, its ``location_bounds_test`` (outside the box FAIL) on these positions."""
    flags = [location_test(lon, lat)]
    if "bbox" in params:
        flags.append(location_bounds_test(lon, lat, params["bbox"]))
    return np.asarray(qartod_compare(flags), dtype=np.uint8)


#: The tests that read the time: ``ioos_qc`` 3.0 counts it in whole seconds (``astype
#: ("timedelta64[s]")``), so a topic sampled faster than 1 Hz would divide by zero.
TIMED = ("rate_of_change_test", "flat_line_test")
#: Per-second parameters of the timed tests: a rate per second (divided by the time
#: scale) and windows in seconds (multiplied by it).
PER_SECOND = {"rate_of_change_test": ("threshold",)}
IN_SECONDS = {"flat_line_test": ("suspect_threshold", "fail_threshold")}
#: The largest span (ns) a scaled series may take: datetime64[ns] is an int64.
MAX_SCALED_SPAN = 2**62


def time_scale(time_ns: np.ndarray) -> int | None:
    """The power of ten by which the timed tests see a sub-second series' time: both
    tests are the same under a change of time unit when their parameters follow it (a
    rate per second divided, windows in seconds multiplied), and at 1,000 s or more a
    median interval loses under 0.1 % to the whole seconds ``ioos_qc`` counts. 1 at
    1 Hz or slower (as ``ioos_qc`` itself); None when no scale brings the interval to a
    second within ``datetime64[ns]`` (repeated times, or a span too long)."""
    if len(time_ns) < 2:
        return 1
    median = float(median_step(np.diff(time_ns)))
    if median >= 1e9:
        return 1
    span = max(int(time_ns[-1]) - int(time_ns[0]), 1)
    scale = 1
    while median * scale < 1e12 and span * scale * 10 < MAX_SCALED_SPAN:
        scale *= 10
    return scale if median * scale >= 1e9 else None


def evaluable(
    tests: dict[str, dict[str, Any]], time_ns: np.ndarray, scale: int | None = 0
) -> dict[str, dict[str, Any]]:
    """``tests`` less the timed ones when the series' time cannot be scaled (``scale``:
    its ``time_scale`` when known, 0 to compute it)."""
    if (time_scale(time_ns) if scale == 0 else scale) is not None:
        return tests
    return {k: v for k, v in tests.items() if k not in TIMED}


def _scaled(name: str, params: dict[str, Any], scale: int) -> dict[str, Any]:
    out = dict(params)
    for key in PER_SECOND.get(name, ()):
        if key in out:
            out[key] = out[key] / scale
    for key in IN_SECONDS.get(name, ()):
        if key in out:
            out[key] = out[key] * scale
    return out


def run_tests(
    tests: dict[str, dict[str, Any]],
    time_ns: np.ndarray,
    value: np.ndarray,
    scale_known: int | None = 0,
) -> np.ndarray:
    """The aggregate flag (uint8) of ``tests`` on one series, as ``ioos_qc`` computes it
    (the timed tests on a sub-second series in scaled time, ``time_scale``; ``scale_known``:
    that scale when known, 0 to compute it)."""
    plain = value.astype(np.float64)
    slow = any(fast_test(k, p) is None for k, p in tests.items())
    inp = np.ma.masked_invalid(plain) if slow else plain  # the library's tests take it masked
    tinp, scale = None, 1
    if any(k in TIMED for k in tests):
        scale = (time_scale(time_ns) if scale_known == 0 else scale_known) or 1
        base = int(time_ns[0]) if len(time_ns) else 0
        tinp = (base + (time_ns.astype(np.int64) - base) * scale).astype("datetime64[ns]")
    flags = []
    for name, params in tests.items():
        fast = fast_test(name, params)  # the same flags, vectorised (qcfast.py)
        fn = fast or _library(name)
        timed = name in TIMED
        args = {"inp": plain if fast else inp} | ({"tinp": tinp} if timed else {})
        flags.append(np.asarray(fn(**args, **(_scaled(name, params, scale) if timed else params))))
    return np.asarray(qartod_compare(flags), dtype=np.uint8)


def _library(name: str) -> Any:
    """``ioos_qc``'s test ``name`` (imported only when a test has no vectorised twin:
    the import costs pandas')."""
    from ioos_qc import qartod

    return getattr(qartod, name)


class QcRunner:
    """Flags each batch of a topic with the context of the topic's last samples."""

    def __init__(self, plan: ExportPlan) -> None:
        self.config = qc_config(plan)
        self.location = location_config(plan)
        self.tails: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.notes: dict[str, str] = {}  # by topic: tests not evaluated, and why

    def location_flags(self, lat: np.ndarray, lon: np.ndarray) -> np.ndarray | None:
        """The location test's flags of these positions; None when it does not run."""
        return None if self.location is None else location_flags(self.location, lat, lon)

    def flags(self, var: Variable, time_ns: np.ndarray, value: np.ndarray) -> np.ndarray | None:
        tests = self.config.get(var.topic)
        if tests is None:
            return None
        t0, v0 = self.tails.get(var.topic, (time_ns[:0], value[:0]))
        t, v = np.concatenate([t0, time_ns]), np.concatenate([v0, value])
        self.tails[var.topic] = (t[-TAIL:], v[-TAIL:])
        scale = time_scale(t) if any(k in TIMED for k in tests) else 1
        run = evaluable(tests, t, scale)
        if len(run) < len(tests):
            self.notes[var.topic] = (
                f"topic {var.topic}: {' and '.join(k for k in tests if k not in run)} not "
                "evaluated: its times repeat or span too long to be scaled to the whole seconds "
                "ioos_qc counts"
            )
        if not run:
            return np.full(len(time_ns), 2, dtype=np.uint8)  # NOT_EVALUATED
        return run_tests(run, t, v, scale)[len(t0) :]
