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
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .plan import ExportPlan, PlanError, Variable
from .qcconfig import QcConfig
from .qcfast import fast_test

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
    unknown = [t for t in given if t not in known]  # one left out by --topics is no error
    if unknown:
        source = plan.metadata.source or "dataset metadata"
        raise PlanError(f"{source}: qc.{unknown[0]}: not a topic of the model ({', '.join(known)})")
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


#: The tests that read the time: ``ioos_qc`` 3.0 counts it in whole seconds (``astype
#: ("timedelta64[s]")``), so a topic sampled faster than 1 Hz would divide by zero.
TIMED = ("rate_of_change_test", "flat_line_test")


def evaluable(tests: dict[str, dict[str, Any]], time_ns: np.ndarray) -> dict[str, dict[str, Any]]:
    """``tests`` less the timed ones when the median interval is under a second."""
    if len(time_ns) < 2 or float(np.median(np.diff(time_ns))) >= 1e9:
        return tests
    return {k: v for k, v in tests.items() if k not in TIMED}


def run_tests(
    tests: dict[str, dict[str, Any]], time_ns: np.ndarray, value: np.ndarray
) -> np.ndarray:
    """The aggregate flag (uint8) of ``tests`` on one series, as ``ioos_qc`` computes it."""
    from ioos_qc import qartod

    plain = value.astype(np.float64)
    inp = np.ma.masked_invalid(plain)
    tinp = time_ns.astype("datetime64[ns]")
    flags = []
    for name, params in tests.items():
        fast = fast_test(name, params)  # the same flags, vectorised (qcfast.py)
        fn = fast or getattr(qartod, name)
        args = {"inp": plain if fast else inp} | ({"tinp": tinp} if name in TIMED else {})
        flags.append(np.asarray(fn(**args, **params)))
    return np.asarray(qartod.qartod_compare(flags), dtype=np.uint8)


class QcRunner:
    """Flags each batch of a topic with the context of the topic's last samples."""

    def __init__(self, plan: ExportPlan) -> None:
        self.config = qc_config(plan)
        self.tails: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.notes: dict[str, str] = {}  # by topic: tests not evaluated, and why

    def flags(self, var: Variable, time_ns: np.ndarray, value: np.ndarray) -> np.ndarray | None:
        tests = self.config.get(var.topic)
        if tests is None:
            return None
        t0, v0 = self.tails.get(var.topic, (time_ns[:0], value[:0]))
        t, v = np.concatenate([t0, time_ns]), np.concatenate([v0, value])
        self.tails[var.topic] = (t[-TAIL:], v[-TAIL:])
        run = evaluable(tests, t)
        if len(run) < len(tests):
            self.notes[var.topic] = (
                f"topic {var.topic}: {' and '.join(k for k in tests if k not in run)} not "
                "evaluated: sampled faster than 1 Hz, and ioos_qc counts time in whole seconds"
            )
        if not run:
            return np.full(len(time_ns), 2, dtype=np.uint8)  # NOT_EVALUATED
        return run_tests(run, t, v)[len(t0) :]
