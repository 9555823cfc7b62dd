"""QARTOD flags of live windows, for the Monitor (docs/user-guide/datasets.md,
"Quality flags", "Live"): each value a subscriber delivers is flagged with the
tests the deployed project configures for its topic (the dataset metadata's
``qc`` section, and a gross range test from the model's ``validMin`` /
``validMax``), run as the export runs them (modd.dataset.qc.run_tests: ``ioos_qc``'s
tests, vectorised, equal flag for flag) on the subscriber's last ``KEEP`` window
values. The browser gets the aggregate flags beside the value: ``{"type":
"value", ..., "qc": [[end_ns, flag], ...]}`` for this window and the one before it
(a spike is known one window late: the test needs the neighbour after it).

A live window is an aggregate (a mean, a minimum...) of the samples it covers:
its flag says that the window's value is suspect or bad by the topic's tests,
not which sample was; the exported file flags each sample.

>>> qc = LiveQc({"spike_test": {"suspect_threshold": 1.0, "fail_threshold": 3.0}})
>>> [qc.flags({"end_ns": i, "value": v}) for i, v in enumerate([1, 1, 9, 1])]
[[[0, 2]], [[0, 2], [1, 2]], [[1, 4], [2, 2]], [[2, 4], [3, 2]]]
"""

from __future__ import annotations

import json
import threading
from collections import deque
from typing import Any

from sqlalchemy.orm import Session as Db

from .deployments import last_acked
from .routers.datasetmeta import head_metadata
from .versions import get_version, model_of

#: Window values kept per subscriber (the tests look back: spike, rate of change, flat line).
KEEP = 256
Tests = dict[str, dict[str, Any]]


class LiveQc:
    """The aggregate QARTOD flag of each new window value of one subscriber."""

    def __init__(self, tests: Tests, keep: int = KEEP) -> None:
        self.tests = tests
        self.times: deque[int] = deque(maxlen=keep)
        self.values: deque[float] = deque(maxlen=keep)
        self._lock = threading.Lock()  # zenoh may call back from more than one thread

    def flags(self, data: Any) -> list[list[int]] | None:
        """``[[end_ns, flag], ...]`` of the window before this one and of this one, as
        ``ioos_qc`` flags the series of the last windows; None for what is no single
        number (a vector, a bool) or a window older than the last."""
        with self._lock:
            return self._flags(data)

    def _flags(self, data: Any) -> list[list[int]] | None:
        import numpy as np
        from modd.dataset.qc import evaluable, run_tests

        if not isinstance(data, dict):
            return None
        end, value = data.get("end_ns"), data.get("value")
        if not isinstance(end, int) or isinstance(value, bool):
            return None
        if not isinstance(value, int | float) or (self.times and end <= self.times[-1]):
            return None  # a backfilled window: its neighbours are not these
        self.times.append(end)
        self.values.append(float(value))
        t = np.fromiter(self.times, dtype=np.int64)
        run = evaluable(self.tests, t)
        if not run:
            return [[end, 2]]  # NOT_EVALUATED
        flags = run_tests(run, t, np.fromiter(self.values, dtype=np.float64))
        return [[int(a), int(f)] for a, f in zip(t[-2:], flags[-2:], strict=True)]


def _variables(model: dict[str, Any]) -> dict[str, dict[str, Any]]:
    drone = model.get("drone") or {}
    out: dict[str, dict[str, Any]] = {}
    for sensor in drone.get("sensors") or []:
        for var in sensor.get("variables") or []:
            out[f"{drone.get('name')}.{sensor.get('name')}.{var.get('name')}"] = var
    return out


def live_tests(db: Db, drone: str) -> dict[str, Tests]:
    """The tests of each subscriber of what runs on ``drone`` (its last acknowledged
    deployment): the model's valid range, then the project's saved ``qc`` section."""
    from modd.dataset.metadata import MetadataError, parse_metadata

    running = last_acked(db, drone)
    if running is None:
        return {}
    model = model_of(get_version(db, running.project_id, running.revision))
    row = head_metadata(db, running.project_id)
    try:
        doc = json.loads(row.metadata_json) if row is not None else {}
        configured = parse_metadata(doc, "metadata").qc
    except MetadataError:
        configured = {}  # saved documents are checked; an older rule's fault flags nothing
    variables = _variables(model)
    out: dict[str, Tests] = {}
    for sub in model.get("subscribers") or []:
        topic = sub.get("topic")
        var = variables.get(topic) or {}
        tests: Tests = {}
        if isinstance(var.get("validMin"), int | float) and isinstance(
            var.get("validMax"), int | float
        ):
            tests["gross_range_test"] = {"fail_span": [var["validMin"], var["validMax"]]}
        tests |= configured.get(topic, {})
        if tests and var.get("type", "float64") != "bool":
            out[str(sub.get("name"))] = tests
    return out
