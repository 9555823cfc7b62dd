"""The drone's track since its mission began, for the Map after a reload: the
latitude and longitude subscribers' windows in the newest base-station record
(``<record_dir>/<drone>/<mission>-<UTC>.mcap``, written by the SubBroker as it
delivers, live and backfilled), paired by time (within ``PAIR_S``) and thinned
to at most ``points`` fixes, evenly over the mission, the first and the last
kept. A record being written is read up to its last complete chunk.

>>> thin(10, 4).tolist()
[0, 3, 6, 9]
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from modd.dataset.received import read_record

from .archives import list_files

#: A latitude and a longitude further apart in time than this are not one fix (s).
PAIR_S = 0.5
MAX_POINTS = 5000


def thin(n: int, points: int) -> np.ndarray:
    """Indices of at most ``points`` of ``n`` items, evenly spread, first and last kept."""
    if n <= points:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max(points, 2)).round().astype(np.int64))


def newest_record(root: Path, drone: str) -> Path | None:
    files = list_files(root, drone)
    return max(files, key=lambda p: (p.stat().st_mtime_ns, p.name)) if files else None


def _series(path: Path, names: set[str]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    parts: dict[str, tuple[list[np.ndarray], list[np.ndarray]]] = {n: ([], []) for n in names}
    for batch in read_record(path, only=names):
        ts, vs = parts[batch.topic]
        ts.append(batch.time_ns)
        vs.append(batch.value.astype(np.float64))
    out = {}
    for key, (ts, vs) in parts.items():
        t = np.concatenate(ts) if ts else np.zeros(0, np.int64)
        v = np.concatenate(vs) if vs else np.zeros(0)
        keep = np.isfinite(v)
        order = np.argsort(t[keep], kind="stable")
        out[key] = (t[keep][order], v[keep][order])
    return out


def pair(lat: tuple[np.ndarray, np.ndarray], lon: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Rows (t_ns, lat, lon): each latitude with the longitude nearest in time, within PAIR_S."""
    (ta, va), (tb, vb) = lat, lon
    if not len(ta) or not len(tb):
        return np.zeros((0, 3))
    j = (
        np.clip(np.searchsorted(tb, ta), 1, len(tb) - 1)
        if len(tb) > 1
        else np.zeros(len(ta), np.int64)
    )
    if len(tb) > 1:
        j = np.where(np.abs(tb[j - 1] - ta) <= np.abs(tb[j] - ta), j - 1, j)
    near = np.abs(tb[j] - ta) <= PAIR_S * 1e9
    return np.column_stack([ta[near].astype(np.float64), va[near], vb[j][near]])


def value_near(series: tuple[np.ndarray, np.ndarray], t_ns: np.ndarray) -> list[float | None]:
    """The value of ``series`` nearest each time, within PAIR_S (None: none that near)."""
    ts, vs = series
    if not len(ts):
        return [None] * len(t_ns)
    j = np.clip(np.searchsorted(ts, t_ns), 0, len(ts) - 1)
    k = np.clip(j - 1, 0, len(ts) - 1)
    j = np.where(np.abs(ts[k] - t_ns) <= np.abs(ts[j] - t_ns), k, j)
    near = np.abs(ts[j] - t_ns) <= PAIR_S * 1e9
    return [float(v) if ok else None for v, ok in zip(vs[j].tolist(), near.tolist(), strict=True)]


def mission_track(
    root: Path, drone: str, lat: str, lon: str, points: int, colour: str | None = None
) -> dict[str, Any]:
    """``{"file", "total", "points": [[t_s, lat, lon], ...]}`` of the newest record
    (``file`` None and no points when the drone has none yet); with ``colour`` a
    fourth column, that subscriber's value at the fix (None when it had none)."""
    path = newest_record(root, drone)
    if path is None:
        return {"file": None, "total": 0, "points": []}
    series = _series(path, {lat, lon} | ({colour} if colour else set()))
    rows = pair(series[lat], series[lon])
    kept = rows[thin(len(rows), points)]
    out: list[list[float | None]] = [[t / 1e9, a, b] for t, a, b in kept.tolist()]
    if colour:
        for row, v in zip(
            out, value_near(series[colour], kept[:, 0].astype(np.int64)), strict=True
        ):
            row.append(v)
    return {"file": path.name, "total": len(rows), "points": out}
