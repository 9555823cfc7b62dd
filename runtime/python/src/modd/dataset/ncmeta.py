"""The NetCDF file's metadata: global attributes (CF-1.11, ACDD-1.3, IOOS-1.2),
the ``platform`` variable and one ``instrument_<sensor>`` variable per sensor.

What MoDD knows it writes (title, summary, keywords, times, bounds, the
model's revision, the platform's and instruments' names); what only the
scientist knows (creator, publisher, license...) comes from the dataset
metadata (metadata.py) and is otherwise left out: never invented.
"""

from __future__ import annotations

import datetime as dt
from importlib import metadata as importlib_metadata
from typing import Any

import numpy as np

from .export import Summary
from .plan import ExportPlan

#: CF-1.11 first (the version the file is written to: readers that parse the attribute
#: take the first CF entry), then CF-1.6: the file is also a CF-1.6 trajectory (every
#: feature it uses is in CF-1.6 but ``units_metadata``, an attribute CF-1.6 ignores; the
#: tests run compliance-checker ``cf:1.6`` on it), and the NCEI trajectory template 2.0,
#: whose checker (cc-plugin-ncei 2.0.4, ``ncei_base.py`` line 1104,
#: ``accepted_conventions = ["CF-1.6", "ACDD-1.3"]``) fails a file, high priority,
#: without the literal "CF-1.6" in the list.
CONVENTIONS = "CF-1.11, CF-1.6, ACDD-1.3, IOOS-1.2"
NCEI_TEMPLATE = "NCEI_NetCDF_Trajectory_Template_v2.0"
STANDARD_NAMES = "CF Standard Name Table v93"


def modd_version() -> str:
    try:
        return importlib_metadata.version("modd-runtime")
    except importlib_metadata.PackageNotFoundError:  # pragma: no cover - a checkout
        return "unknown"


def iso(ns: int | None) -> str:
    if ns is None:
        return ""
    return dt.datetime.fromtimestamp(ns / 1e9, dt.UTC).isoformat().replace("+00:00", "Z")


def _what(plan: ExportPlan) -> dict[str, str]:
    """The attributes that say what the dataset holds: samples or received windows."""
    if plan.source == "received":
        return {
            "title": f"{plan.description}: windows received from drone {plan.drone}",
            "summary": (
                f"Every window the MoDD subscribers of drone {plan.drone} received (the "
                "base-station record, live and backfilled), at the window's end, with the "
                "platform position interpolated from the received position windows."
            ),
            "source": "MoDD base-station record (MCAP)",
            "processing_level": "aggregated on board per subscription (cell_methods); "
            "position interpolated",
        }
    return {
        "title": f"{plan.description}: samples of drone {plan.drone}",
        "summary": (
            f"Every sample archived on board drone {plan.drone} by the MoDD PubBroker, "
            "at its own time, with the platform position linearly interpolated to it."
        ),
        "source": "MoDD on-board archive (MCAP)",
        "processing_level": "raw samples; position interpolated",
    }


def global_attributes(plan: ExportPlan) -> dict[str, Any]:
    now = dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")
    names = sorted({v.standard_name for v in plan.variables.values() if v.standard_name})
    declared = plan.metadata.attributes
    attrs: dict[str, Any] = {
        "Conventions": CONVENTIONS,
        "featureType": "trajectory",
        "cdm_data_type": "Trajectory",
        "cdm_trajectory_variables": "trajectory",
        "ncei_template_version": NCEI_TEMPLATE,
        **_what(plan),
        "keywords": ", ".join(["drone", "trajectory", "in situ", *names]),
        # ACDD/IOOS: the platform's type from platform_vocabulary (one word), else the drone
        "platform": "_".join((plan.metadata.platform.get("type") or plan.drone).split()),
        "platform_name": plan.metadata.platform.get("name") or plan.description,
        "history": f"{now} modd dataset (MoDD {modd_version()})",
        "date_created": now,
        "date_modified": now,
        "date_issued": now,
        "product_version": modd_version(),
        "modd_version": modd_version(),
        "modd_model_revision": plan.model_revision,
        "id": f"{plan.drone}-{plan.model_revision}",
        "comment": "Positions are linear interpolations between the platform's fixes; a sample "
        "in a gap longer than the model's maxGap has none (fill value).",
        "standard_name_vocabulary": STANDARD_NAMES,
    }
    if "platform_id" not in declared and "id" in plan.metadata.platform:
        attrs["platform_id"] = plan.metadata.platform["id"]
    if "vocabulary" in plan.metadata.platform:
        attrs["platform_vocabulary"] = plan.metadata.platform["vocabulary"]
    makes = [_make_model(i) for i in plan.metadata.instruments.values()]
    if any(makes):
        attrs["instrument"] = ", ".join(m for m in makes if m)
    return attrs | declared


def _make_model(declared: dict[str, str]) -> str:
    return " ".join(declared[k] for k in ("make", "model") if k in declared)


def coverage(ds: Any, s: Summary, plan: ExportPlan, period_s: float | None = None) -> None:
    """Time and space covered (ACDD), once the samples are written."""
    if s.start_ns is not None and s.end_ns is not None:
        ds.time_coverage_start, ds.time_coverage_end = iso(s.start_ns), iso(s.end_ns)
        ds.time_coverage_duration = f"PT{(s.end_ns - s.start_ns) / 1e9:.3f}S"
    if period_s is not None:
        ds.time_coverage_resolution = f"PT{period_s:g}S"
    for key, rng, units in (
        ("lat", s.lat_range, "degree_north"),
        ("lon", s.lon_range, "degree_east"),
    ):
        if rng is not None:
            setattr(ds, f"geospatial_{key}_min", rng[0])
            setattr(ds, f"geospatial_{key}_max", rng[1])
            setattr(ds, f"geospatial_{key}_units", units)
    if s.lat_range is not None and s.lon_range is not None:
        (la0, la1), (lo0, lo1) = s.lat_range, s.lon_range
        ds.geospatial_bounds = (
            f"POLYGON (({la0} {lo0}, {la1} {lo0}, {la1} {lo1}, {la0} {lo1}, {la0} {lo0}))"
        )
        ds.geospatial_bounds_crs = "EPSG:4326"
    if s.alt_range is not None:
        ds.geospatial_vertical_min, ds.geospatial_vertical_max = s.alt_range
        ds.geospatial_vertical_units, ds.geospatial_vertical_positive = "m", "up"


def platform_variable(ds: Any, plan: ExportPlan) -> None:
    """``platform`` (IOOS 1.2): the drone, with what the metadata says of it."""
    declared = plan.metadata.platform
    v = ds.createVariable("platform", "i1", ())
    attrs: dict[str, Any] = {
        "long_name": declared.get("name") or plan.description,
        "comment": declared.get("comment") or f"MoDD drone {plan.drone}",
    }
    for key in ("type", "ioos_code", "wmo_code"):
        if key in declared:
            attrs[key] = declared[key]
    if "id" in declared:
        attrs["platform_id"] = declared["id"]
    if "vocabulary" in declared:
        attrs["platform_vocabulary"] = declared["vocabulary"]
    v.setncatts(attrs)
    v.assignValue(np.int8(0))


def instrument_variables(ds: Any, plan: ExportPlan) -> dict[str, str]:
    """One ``instrument_<sensor>`` per sensor with a variable in the file; by sensor name."""
    used = {v.sensor for v in plan.variables.values() if v.sensor is not None}
    out: dict[str, str] = {}
    for sensor, description in plan.sensors.items():
        if sensor not in used:
            continue
        name = f"instrument_{sensor}"
        declared = plan.metadata.instruments.get(sensor, {})
        v = ds.createVariable(name, "i1", ())
        attrs: dict[str, Any] = {"long_name": description, "modd_sensor": sensor}
        attrs |= {k: val for k, val in declared.items() if k != "comment"}
        make_model = _make_model(declared)
        if make_model:
            attrs["make_model"] = make_model
        if "comment" in declared:
            attrs["comment"] = declared["comment"]
        v.setncatts(attrs)
        v.assignValue(np.int8(0))
        out[sensor] = name
    return out
