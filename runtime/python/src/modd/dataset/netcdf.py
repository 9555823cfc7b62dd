"""NetCDF-4: CF-1.11 ``featureType = "trajectory"`` with ACDD-1.3 global attributes.

Layout (docs/user-guide/datasets.md, "NetCDF layout"): every topic keeps its
own samples at its own times, so each has its own observation dimension
``obs_<name>`` with its own coordinates ``time_<name>``, ``lat_<name>``,
``lon_<name>``, ``alt_<name>`` (the platform position interpolated to those
times); the data variable ``<name>`` names them in ``coordinates``. Nothing is
resampled: variables at 25 Hz and 0.5 Hz sit side by side, each a CF
single-trajectory ``data(o)`` (CF §9, H.4.1) of the one trajectory named by the
scalar ``trajectory`` (``cf_role = "trajectory_id"``). With ``--resample`` the
wide table has one ``obs`` dimension and plain ``time lat lon alt``.
"""

from __future__ import annotations

import datetime as dt
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from .export import Summary
from .plan import ExportPlan, Variable
from .position import Track
from .record import dtype_of
from .resample import WideTable

_INT_FILL = {np.dtype(np.int64): np.int64(-(2**63)), np.dtype(np.int8): np.int8(-127)}
TIME_UNITS = "seconds since 1970-01-01 00:00:00"
CHUNK = 16384
#: HDF5 chunk cache per variable (the library's default is megabytes per variable, and a
#: dataset of 20 topics has 100 variables): a few chunks each is all a stream needs.
CACHE_BYTES = 4 * CHUNK * 8
#: Standard names CF reads as vertical coordinates, which then need ``positive``.
_VERTICAL = {
    "altitude": "up",
    "height": "up",
    "height_above_mean_sea_level": "up",
    "height_above_geoid": "up",
    "height_above_reference_ellipsoid": "up",
    "depth": "down",
    "depth_below_geoid": "down",
}


def modd_version() -> str:
    try:
        return metadata.version("modd-runtime")
    except metadata.PackageNotFoundError:  # pragma: no cover - a checkout without install
        return "unknown"


def _iso(ns: int | None) -> str:
    if ns is None:
        return ""
    return dt.datetime.fromtimestamp(ns / 1e9, dt.UTC).isoformat().replace("+00:00", "Z")


def _coord(ds: Any, name: str, dim: str, kind: str) -> None:
    attrs = {
        # Unix time counts no leap seconds
        "time": {
            "units": TIME_UNITS,
            "standard_name": "time",
            "long_name": "time of the sample",
            "calendar": "standard",
            "axis": "T",
            "units_metadata": "leap_seconds: none",
        },
        "lat": {
            "units": "degree_north",
            "standard_name": "latitude",
            "axis": "Y",
            "long_name": "platform latitude, interpolated to the sample's time",
        },
        "lon": {
            "units": "degree_east",
            "standard_name": "longitude",
            "axis": "X",
            "long_name": "platform longitude, interpolated to the sample's time",
        },
        "alt": {
            "units": "m",
            "standard_name": "altitude",
            "axis": "Z",
            "positive": "up",
            "long_name": "platform altitude, interpolated to the sample's time",
        },
    }[kind]
    fill = None if kind == "time" else np.nan
    v = ds.createVariable(
        name, "f8", (dim,), fill_value=fill, chunksizes=(CHUNK,), zlib=True, complevel=1
    )
    v.set_var_chunk_cache(size=CACHE_BYTES)
    v.setncatts(attrs | {"coverage_content_type": "coordinate"})


def _data_var(ds: Any, var: Variable, name: str, dim: str, coords: str) -> None:
    dtype = np.dtype(dtype_of(var.value_type))
    fill = np.float32(np.nan) if dtype.kind == "f" else _INT_FILL[dtype]
    v = ds.createVariable(
        name, dtype, (dim,), fill_value=fill, chunksizes=(CHUNK,), zlib=True, complevel=1
    )
    v.set_var_chunk_cache(size=CACHE_BYTES)
    attrs: dict[str, Any] = {
        "long_name": var.long_name,
        "coordinates": coords,
        "modd_topic": var.topic,
        "coverage_content_type": "physicalMeasurement",
    }
    if var.standard_name in _VERTICAL:
        attrs["positive"] = _VERTICAL[var.standard_name]
    if var.temperature:
        attrs["units_metadata"] = "temperature: on_scale"
    if var.value_type == "bool":
        attrs |= {"flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "false true"}
    else:
        attrs["units"] = var.unit
    if var.standard_name:
        attrs["standard_name"] = var.standard_name
    if var.cell_methods:
        attrs["cell_methods"] = var.cell_methods
    if var.valid_min is not None:
        attrs["valid_min"] = np.array(var.valid_min, dtype=dtype)
    if var.valid_max is not None:
        attrs["valid_max"] = np.array(var.valid_max, dtype=dtype)
    v.setncatts(attrs)


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


def _globals(plan: ExportPlan) -> dict[str, Any]:
    now = dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")
    return {
        "Conventions": "CF-1.11, ACDD-1.3",
        "featureType": "trajectory",
        "cdm_data_type": "Trajectory",
        **_what(plan),
        "keywords": "drone, trajectory, in situ, "
        + ", ".join(sorted({v.standard_name for v in plan.variables.values() if v.standard_name})),
        "platform": plan.drone,
        "history": f"{now} modd dataset (MoDD {modd_version()})",
        "date_created": now,
        "product_version": modd_version(),
        "modd_version": modd_version(),
        "modd_model_revision": plan.model_revision,
        "id": f"{plan.drone}-{plan.model_revision}",
        "naming_authority": "modd",
        "comment": "Positions are linear interpolations between the platform's fixes; a sample "
        "in a gap longer than the model's maxGap has none (fill value).",
        "standard_name_vocabulary": "CF Standard Name Table v93",
    }


def _coverage(ds: Any, s: Summary) -> None:
    if s.start_ns is not None and s.end_ns is not None:
        ds.time_coverage_start, ds.time_coverage_end = _iso(s.start_ns), _iso(s.end_ns)
        ds.time_coverage_duration = f"PT{(s.end_ns - s.start_ns) / 1e9:.3f}S"
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


def _trajectory(ds: Any, plan: ExportPlan) -> None:
    t = ds.createVariable("trajectory", str, ())
    t.cf_role = "trajectory_id"
    t.long_name = "mission of the drone"
    t[...] = np.array(f"{plan.drone}-{plan.model_revision}", dtype=object)


class NetcdfSink:
    """The long form: one observation dimension per topic."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.ds: Any = None
        self.filled: dict[str, int] = {}

    def open(self, plan: ExportPlan, track: Track | None) -> None:
        import netCDF4

        self.ds = netCDF4.Dataset(self.path, "w", format="NETCDF4")
        self.ds.setncatts(_globals(plan))
        _trajectory(self.ds, plan)
        for var in plan.variables.values():
            dim = f"obs_{var.name}"
            self.ds.createDimension(dim, None)
            names = [f"{k}_{var.name}" for k in ("time", "lat", "lon", "alt")]
            for kind, name in zip(("time", "lat", "lon", "alt"), names, strict=True):
                _coord(self.ds, name, dim, kind)
            _data_var(self.ds, var, var.name, dim, " ".join(names))
            self.filled[var.name] = 0

    def write(
        self,
        var: Variable,
        time_ns: np.ndarray,
        value: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
    ) -> None:
        at, n = self.filled[var.name], len(time_ns)
        sl = slice(at, at + n)
        self.ds[f"time_{var.name}"][sl] = time_ns / 1e9
        self.ds[f"lat_{var.name}"][sl] = lat
        self.ds[f"lon_{var.name}"][sl] = lon
        self.ds[f"alt_{var.name}"][sl] = alt
        self.ds[var.name][sl] = value
        self.filled[var.name] = at + n

    def close(self, plan: ExportPlan, summary: Summary) -> None:
        _coverage(self.ds, summary)
        self.ds.close()


def write_wide(path: Path, plan: ExportPlan, table: WideTable, summary: Summary) -> None:
    """The resampled form: one ``obs`` dimension, ``time lat lon alt`` shared."""
    import netCDF4

    with netCDF4.Dataset(path, "w", format="NETCDF4") as ds:
        ds.setncatts(_globals(plan))
        ds.processing_level = f"resampled: mean over {table.period_s:g} s periods"
        _trajectory(ds, plan)
        ds.createDimension("obs", len(table.time_ns))
        for kind in ("time", "lat", "lon", "alt"):
            _coord(ds, kind, "obs", kind)
        ds["time"][:] = table.time_ns / 1e9
        ds["lat"][:], ds["lon"][:], ds["alt"][:] = table.lat, table.lon, table.alt
        for var in plan.variables.values():
            mean = Variable(
                var.topic,
                var.name,
                var.unit,
                "float64",
                var.standard_name,
                var.long_name,
                var.valid_min,
                var.valid_max,
                var.temperature,
            )
            _data_var(ds, mean, var.name, "obs", "time lat lon alt")
            ds[var.name].cell_methods = f"time: mean (interval: {table.period_s:g} s)"
            ds[var.name][:] = table.columns[var.topic]
        _coverage(ds, summary)
