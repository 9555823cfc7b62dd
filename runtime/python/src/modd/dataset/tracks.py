"""The track as GeoJSON (a FeatureCollection: the track, then one Point per
period carrying the chosen measurements as properties) and GPX 1.1 (one
track segment; measurements in each point's ``<extensions>``, in the MoDD
namespace ``GPX_NS``, each with its ``unit``). Both are written from the
wide form (one point per resampling period, 1 s unless ``--resample`` says),
one point at a time; points without a position are left out (and counted).
The track is a LineString from two points on, a Point with one (RFC 7946: a
LineString has two positions or more), and absent with none.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from .export import Summary
from .plan import ExportPlan
from .resample import WideTable

#: The namespace of MoDD's GPX extensions (docs/user-guide/datasets.md, "GPX").
GPX_NS = "https://modd.dev/schema/gpx/1"


def _iso(ns: int) -> str:
    t = dt.datetime.fromtimestamp(ns // 1_000_000_000, dt.UTC)
    return t.strftime("%Y-%m-%dT%H:%M:%S") + f".{ns % 1_000_000_000 // 1000:06d}Z"


def _positioned(table: WideTable) -> np.ndarray:
    return np.flatnonzero(np.isfinite(table.lat) & np.isfinite(table.lon))


def _props(plan: ExportPlan, table: WideTable, i: int) -> dict[str, float | None]:
    out: dict[str, float | None] = {}
    for var in plan.variables.values():
        v = float(table.columns[var.topic][i])
        out[var.name] = v if math.isfinite(v) else None
    return out


def write_geojson(path: Path, plan: ExportPlan, table: WideTable, summary: Summary) -> None:
    rows = _positioned(table)
    _note_unplaced(table, rows, summary)
    with path.open("w", encoding="utf-8") as f:
        units = {v.name: v.unit for v in plan.variables.values()}
        f.write('{"type":"FeatureCollection","features":[')
        line = [[round(float(table.lon[i]), 8), round(float(table.lat[i]), 8)] for i in rows]
        sep = ""
        if line:
            geometry = (
                {"type": "LineString", "coordinates": line}
                if len(line) > 1
                else {"type": "Point", "coordinates": line[0]}
            )
            props = {"drone": plan.drone, "units": units, "period_s": table.period_s}
            f.write(json.dumps({"type": "Feature", "geometry": geometry, "properties": props}))
            sep = ",\n"
        for i in rows:
            coords = [float(table.lon[i]), float(table.lat[i])]
            if math.isfinite(table.alt[i]):
                coords.append(float(table.alt[i]))
            props = {"time": _iso(int(table.time_ns[i])), **_props(plan, table, i)}
            f.write(
                sep
                + json.dumps(
                    {
                        "type": "Feature",
                        "properties": props,
                        "geometry": {"type": "Point", "coordinates": coords},
                    }
                )
            )
        f.write("]}\n")


def write_gpx(path: Path, plan: ExportPlan, table: WideTable, summary: Summary) -> None:
    rows = _positioned(table)
    units = {v.name: escape(v.unit, {'"': "&quot;"}) for v in plan.variables.values()}
    _note_unplaced(table, rows, summary)
    with path.open("w", encoding="utf-8") as f:
        f.write(
            '<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<gpx version="1.1" creator="MoDD modd dataset" '
            f'xmlns="http://www.topografix.com/GPX/1/1" xmlns:modd="{GPX_NS}">\n'
            f"<trk><name>{escape(plan.drone)}</name><trkseg>\n"
        )
        for i in rows:
            f.write(f'<trkpt lat="{table.lat[i]:.8f}" lon="{table.lon[i]:.8f}">')
            if math.isfinite(table.alt[i]):
                f.write(f"<ele>{table.alt[i]:.3f}</ele>")
            f.write(f"<time>{_iso(int(table.time_ns[i]))}</time><extensions>")
            for name, v in _props(plan, table, i).items():
                if v is not None:
                    f.write(f'<modd:{name} unit="{units[name]}">{v!r}</modd:{name}>')
            f.write("</extensions></trkpt>\n")
        f.write("</trkseg></trk>\n</gpx>\n")


def _note_unplaced(table: WideTable, rows: np.ndarray, summary: Summary) -> None:
    left = len(table.time_ns) - len(rows)
    if left:
        summary.notes.append(
            f"{left} of {len(table.time_ns)} track points have no position and were left out"
        )
