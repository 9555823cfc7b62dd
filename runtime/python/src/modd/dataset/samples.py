"""An archive's samples by topic, for the planner's calibration (``modd plan
MODEL --calibrate ARCHIVE.mcap``: docs/planning.md, "Bounds and estimates").

Registered as the ``mcap`` entry point of the group ``modd.samples``
(runtime/python/pyproject.toml), which the planner's command line looks up:
the metamodel never imports the runtime.

>>> series = read_samples(Path("usv-20260101T000000Z-0000.mcap"), {"usv.a.x"})  # doctest: +SKIP
>>> stamps_ns, values = series["usv.a.x"]  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Collection
from pathlib import Path

import numpy as np
from modd_plan.calibration import SAMPLES_LIMIT, CalibrationError, Series

from .mcapread import ArchiveError, FileState, read_file
from .record import RecordError


def read_samples(
    path: Path, topics: Collection[str], limit: int = SAMPLES_LIMIT
) -> dict[str, Series]:
    """The first ``limit`` samples of each of ``topics`` in the archive, by
    topic (log time in ns, ascending; values as floats); topics without a
    sample are left out. Reading stops once every topic has ``limit`` (the
    archive's chunks follow each other in time). A missing, unreadable or
    corrupt file is a :class:`CalibrationError` naming the file (and the byte
    offset of a corrupt record). A file cut short is read up to its last
    complete record."""
    stamps: dict[str, list[np.ndarray]] = {}
    values: dict[str, list[np.ndarray]] = {}
    counts = dict.fromkeys(topics, 0)
    try:
        for batch in read_file(path, FileState(path), only=set(topics)):
            if counts.get(batch.topic, limit) >= limit:
                if all(n >= limit for n in counts.values()):
                    break
                continue
            counts[batch.topic] += len(batch.time_ns)
            stamps.setdefault(batch.topic, []).append(batch.time_ns)
            values.setdefault(batch.topic, []).append(batch.value.astype(np.float64))
    except ArchiveError as exc:
        raise CalibrationError(str(exc)) from None
    except RecordError as exc:
        raise CalibrationError(f"{path}: {exc}") from None
    except OSError as exc:
        raise CalibrationError(f"{path}: {exc.strerror or exc}") from None
    out: dict[str, Series] = {}
    for topic, parts in stamps.items():
        t = np.concatenate(parts)
        order = np.argsort(t, kind="stable")[:limit]  # file order is time order; make sure
        out[topic] = (t[order].tolist(), np.concatenate(values[topic])[order].tolist())
    return {k: v for k, v in out.items() if len(v[0])}
