"""What the subscribers received: the windows of the base-station record
(``modd.subbroker.record``: one MCAP per drone and mission, one channel
``modd/<drone>/sub/<subscriber>`` per subscriber, each message a delivered
value, contract ``delivered_value``) exported like the archive's samples.

A subscriber is a variable: its windows at their end (the time a viewer plots
them), the unit of its topic, a CF ``cell_methods`` saying how the window was
aggregated (``time: mean``, ``time: minimum``...). An empty window is a fill
value; an ``ALL`` window is its samples, spread over the window as the
contract says (the last at the window's end). The position is interpolated
from the windows of the subscribers of the platform's position topics: what
the base station knew, not the archive's fixes.

>>> cell_methods("AVERAGE", "0.25")
'time: mean (interval: 0.25 s)'
>>> window_points(0, 1_000_000_000, [1.0, 2.0])
(array([ 500000000, 1000000000]), array([1., 2.]))
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from modd_contracts import aggregations_gen as agg
from modd_contracts import labels
from modd_contracts.keys import match_sub_key
from modd_model.position import PlatformPosition

from .mcapread import ArchiveError, Batch, FileState
from .plan import ExportPlan, PlanError, Variable, _safe, plan_export

#: Messages decoded before their batches are handed on (memory bound).
FLUSH = 8192
_METHODS = {
    agg.AVERAGE: "mean",
    agg.MIN: "minimum",
    agg.MAX: "maximum",
    agg.LAST: "point",
    agg.ALL: "point",
    agg.MEDIAN: "median",
    agg.STDDEV: "standard_deviation",
    agg.RANGE: "range",
}


def cell_methods(aggregation: str, period_s: str) -> str | None:
    """CF ``cell_methods`` of a window (CF §7.3); None for COUNT (not a statistic
    of the variable: its own variable, unit ``1``) and for PERCENTILE(p): CF's
    methods (Appendix E) have no percentile and ``point`` would claim an
    instantaneous value, so its ``long_name`` says which percentile it is."""
    method = _METHODS.get(aggregation)
    if method is None:
        return None
    if method == "point":
        return "time: point"
    return f"time: {method} (interval: {float(period_s):g} s)"


def window_points(start_ns: int, end_ns: int, value: Any) -> tuple[np.ndarray, np.ndarray]:
    """The (time, value) points of one window: its end and value, an ``ALL``
    window's samples spread over it, a fill value (NaN) for an empty window."""
    if isinstance(value, list):
        if not value:
            return np.array([end_ns], np.int64), np.array([np.nan])
        n = len(value)
        k = np.arange(1, n + 1, dtype=np.int64)
        times = start_ns + (k * (end_ns - start_ns)) // n
        return times, np.array([_number(v) for v in value], np.float64)
    return np.array([end_ns], np.int64), np.array([_number(value)], np.float64)


def _number(v: Any) -> float:
    if isinstance(v, bool | int | float):
        return float(v)
    return float("nan")


def _subscriber_variable(sub: dict[str, Any], topic: Variable | None) -> Variable:
    name, aggregation, period = sub["name"], labels.of_subscriber(sub), str(sub["periodS"])
    what = f"{aggregation} of {sub['topic']} over {float(period):g} s windows"
    if "percentile" in sub:
        what += " (numpy.percentile, linear)"
    if aggregation == agg.COUNT or topic is None:
        return Variable(
            sub["name"],
            _safe(name),
            "1",
            "float64",
            None,
            f"{what} (subscriber {name})",
            None,
            None,
        )
    return replace(
        topic,
        topic=name,
        name=_safe(name),
        value_type="float64",
        long_name=f"{what} (subscriber {name})",
        cell_methods=cell_methods(aggregation, period),
        instrument_clock=False,  # a window's time is its end on the base station's axis
    )


def _position(subs: list[dict[str, Any]], pos: PlatformPosition | None) -> PlatformPosition | None:
    """The platform position as subscriber names: a subscriber of each
    position topic (the shortest period), or None without latitude and longitude."""
    if pos is None:
        return None

    def of(topic: str | None) -> str | None:
        found = [s for s in subs if s["topic"] == topic and s["aggregation"] != agg.COUNT]
        return min(found, key=lambda s: float(s["periodS"]))["name"] if found else None

    lat, lon = of(pos.latitude), of(pos.longitude)
    if lat is None or lon is None:
        return None
    return replace(pos, latitude=lat, longitude=lon, altitude=of(pos.altitude))


def plan_received(
    model: dict[str, Any],
    names: list[str] | None,
    start_ns: int | None = None,
    end_ns: int | None = None,
) -> ExportPlan:
    """The plan for the subscribers ``names`` (subscriber names or topics; all
    when None). Raises PlanError."""
    base = plan_export(model, None, start_ns, end_ns)
    subs = [s for s in model.get("subscribers", []) if not s.get("dynamic")]
    if names:
        known = {s["name"] for s in subs} | {s["topic"] for s in subs}
        short = {t.split(".", 1)[1]: t for t in base.variables}
        wanted = {short.get(n, n) for n in names}
        unknown = sorted(n for n in names if short.get(n, n) not in known)
        if unknown:
            raise PlanError(
                f"no subscriber of {', '.join(unknown)}; the model's subscribers "
                f"are {', '.join(s['name'] for s in subs)}"
            )
        chosen = [s for s in subs if s["name"] in wanted or s["topic"] in wanted]
    else:
        chosen = subs
    variables = {s["name"]: _subscriber_variable(s, base.variables.get(s["topic"])) for s in chosen}
    return replace(
        base, variables=variables, position=_position(subs, base.position), source="received"
    )


def read_record(
    path: Path,
    state: FileState | None = None,
    progress: Callable[[int], None] | None = None,
    only: set[str] | None = None,
) -> Iterator[Batch]:
    """Every window of a base-station record as batches (one per subscriber
    per ``FLUSH`` messages); a cut file is read up to its last complete record."""
    from mcap.exceptions import EndOfFile, McapError
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    st = state if state is not None else FileState(path)
    st.size = path.stat().st_size
    names: dict[int, str] = {}
    parts: _Parts = {}
    held = 0
    with open(path, "rb") as f:
        try:
            for rec in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(rec, Channel):
                    found = match_sub_key(rec.topic)
                    if found is not None:
                        names[rec.id] = found[1]
                        st.topics[rec.id] = (found[1], "float64")
                elif isinstance(rec, Message) and names.get(rec.channel_id) is not None:
                    name = names[rec.channel_id]
                    if only is not None and name not in only:
                        continue
                    for part, got in zip(
                        parts.setdefault(name, ([], [], [])),
                        _window(path, f.tell(), rec.data),
                        strict=True,
                    ):
                        part.append(got)
                    held += 1
                    if held >= FLUSH:
                        yield from _flush(parts)
                        held = 0
                        if progress:
                            progress(f.tell())
            st.closed = True
        except (EndOfFile, EOFError, struct.error):
            st.cut_at = f.tell()
        except McapError as exc:
            raise ArchiveError(path, f.tell(), f"not a readable MCAP record ({exc})") from None
    yield from _flush(parts)
    if progress:
        progress(st.size)


def _window(path: Path, offset: int, data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A window's points, each marked historical when it was delivered by backfill."""
    try:
        doc = json.loads(data)
        times, values = window_points(int(doc["start_ns"]), int(doc["end_ns"]), doc.get("value"))
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ArchiveError(path, offset, f"not a delivered value ({exc})") from None
    return times, values, np.full(len(times), doc.get("backfilled") is True)


#: Per subscriber, the windows' times, values and historical marks not yet handed on.
_Parts = dict[str, tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]]


def _flush(parts: _Parts) -> Iterator[Batch]:
    for name, (ts, vs, hs) in parts.items():
        if ts:
            t, v, h = np.concatenate(ts), np.concatenate(vs), np.concatenate(hs)
            yield Batch(name, "float64", t, v, None, h)
    parts.clear()
