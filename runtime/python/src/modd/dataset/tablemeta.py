"""What Parquet and CSV carry besides the values: the schema's metadata (the
``modd`` key: each topic's unit, CF standard name and long name, the model's
revision, the dataset metadata; ``geo``: GeoParquet 1.1), the positions as
WKB points, and ISO 8601 times for CSV.

>>> str(iso_times(np.array([1_790_000_000_000_000_001]))[0])
'2026-09-21T14:13:20.000000001Z'
>>> bytes(wkb_points(np.array([-3.0]), np.array([47.0]))[0].as_py()).hex()[:10]
'0101000000'
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from .ncmeta import modd_version
from .plan import ExportPlan, Variable

GEOPARQUET_VERSION = "1.1.0"
_WKB_POINT = np.dtype([("order", "u1"), ("kind", "<u4"), ("x", "<f8"), ("y", "<f8")])


def iso_times(time_ns: np.ndarray) -> np.ndarray:
    """ns since the Unix epoch as ISO 8601 UTC text, nanoseconds kept."""
    text: np.ndarray = np.char.add(
        np.datetime_as_string(time_ns.astype("datetime64[ns]"), unit="ns"), "Z"
    )
    return text


def wkb_points(lon: np.ndarray, lat: np.ndarray) -> Any:
    """Little-endian WKB points (x = longitude, y = latitude); null where either is NaN."""
    import pyarrow as pa
    import pyarrow.compute as pc

    rec = np.empty(len(lon), _WKB_POINT)
    rec["order"], rec["kind"], rec["x"], rec["y"] = 1, 1, lon, lat
    fixed = pa.FixedSizeBinaryArray.from_buffers(
        pa.binary(_WKB_POINT.itemsize), len(rec), [None, pa.py_buffer(rec.tobytes())]
    )
    missing = pa.array(~(np.isfinite(lon) & np.isfinite(lat)))
    return pc.if_else(missing, pa.scalar(None, pa.binary()), fixed.cast(pa.binary()))


def _describe(v: Variable) -> dict[str, Any]:
    out: dict[str, Any] = {"name": v.name, "units": v.unit, "long_name": v.long_name}
    for key, value in (
        ("standard_name", v.standard_name),
        ("valid_min", v.valid_min),
        ("valid_max", v.valid_max),
        ("cell_methods", v.cell_methods),
        ("sensor", v.sensor),
    ):
        if value is not None:
            out[key] = value
    return out


def _geo(bbox: list[float] | None = None) -> dict[str, Any]:
    column: dict[str, Any] = {"encoding": "WKB", "geometry_types": ["Point"]}
    if bbox is not None:
        column["bbox"] = bbox
    return {
        "version": GEOPARQUET_VERSION,
        "primary_column": "geometry",
        "columns": {"geometry": column},
    }


def schema_metadata(
    plan: ExportPlan, *, long_form: bool, period_s: float | None = None
) -> dict[str, str]:
    """The Parquet schema's key-value metadata (``modd``, ``geo``; the wide form's
    ``unit:<column>`` and ``resample_period_s`` too)."""
    modd: dict[str, Any] = {
        "drone": plan.drone,
        "source": plan.source,
        "model_revision": plan.model_revision,
        "modd_version": modd_version(),
        "form": "long" if long_form else "wide",
        "topics": {topic: _describe(v) for topic, v in plan.variables.items()},
        "time": "UTC, ns since 1970-01-01 (no leap seconds)",
        "position": "platform position interpolated to each row's time (WGS 84)",
        "metadata": plan.metadata.attributes,
    }
    out = {"modd": json.dumps(modd), "geo": json.dumps(_geo())}
    if period_s is not None:
        modd["resample_period_s"] = period_s
        out["modd"] = json.dumps(modd)
        out |= {f"unit:{v.name}": v.unit for v in plan.variables.values()}
        out["resample_period_s"] = f"{period_s:g}"
    return out


def with_field_metadata(schema: Any, plan: ExportPlan) -> Any:
    """The wide form's schema with each topic column's units, standard and long name."""
    by_name = {v.name: v for v in plan.variables.values()}
    fixed = {
        "lat": {"units": "degree_north", "standard_name": "latitude"},
        "lon": {"units": "degree_east", "standard_name": "longitude"},
        "alt": {"units": "m", "standard_name": "altitude"},
    }
    fields = []
    for f in schema:
        if f.name in by_name:
            meta = {k: str(v) for k, v in _describe(by_name[f.name]).items() if k != "name"}
        else:
            meta = fixed.get(f.name, {})
        fields.append(f.with_metadata(meta) if meta else f)
    import pyarrow as pa

    return pa.schema(fields)
