"""NetCDF-4: a CF-1.11 discrete sampling geometry, ``featureType =
"trajectory"``, with ACDD-1.3 and IOOS-1.2 metadata.

Layout (docs/user-guide/datasets.md, "NetCDF layout"): the incomplete
multidimensional representation of CF §9.3.2 (H.4.2) with one trajectory:
dimensions ``trajectory`` (1) and ``obs`` (unlimited); ``trajectory(trajectory,
name_strlen)`` carries ``cf_role = "trajectory_id"``; ``time``, ``lat``,
``lon``, ``alt`` and every data variable are ``(trajectory, obs)``. Each
observation is one sample of one topic: its own variable holds the value,
the others the fill value. Nothing is resampled (25 Hz and 0.5 Hz topics sit
side by side, at their own times) and the file is written as the archive is
read (rows in blocks of one topic, time-ordered within a topic), so memory
stays bounded; an unwritten block of a variable is not stored (HDF5 leaves
its chunks unallocated). With ``--resample`` the rows are the periods and
every variable has a value in most of them. ``platform`` and one
``instrument_<sensor>`` variable per sensor describe where the data come from
(IOOS 1.2); a data variable names them in ``platform`` and ``instrument``. An
ancillary variable (a quality flag) is one more ``(trajectory, obs)`` variable
written beside its data variable (``_data_var`` and ``NetcdfSink.write``).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from .export import NAT, Summary
from .ncmeta import coverage, global_attributes, instrument_variables, platform_variable
from .plan import ExportPlan, PlanError, Variable
from .position import Track
from .qc import FLAG_ATTRS, location_config, qc_config
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


DIMS = ("trajectory", "obs")


def _obs_var(ds: Any, name: str, dtype: Any, fill: Any) -> Any:
    """A ``(trajectory, obs)`` variable: chunks of ``CHUNK`` observations, deflated
    (level 1) after HDF5's byte shuffle (netCDF4's default with zlib, stated: without
    it zlib costs ~3x the CPU on these columns and the file is ~4x larger), with a
    small chunk cache."""
    v = ds.createVariable(
        name,
        dtype,
        DIMS,
        fill_value=fill,
        chunksizes=(1, CHUNK),
        zlib=True,
        complevel=1,
        shuffle=True,
    )
    v.set_var_chunk_cache(size=CACHE_BYTES)
    return v


def _coord(ds: Any, name: str, kind: str) -> None:
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
    fill = None if kind == "time" else np.nan  # every observation has its time
    v = _obs_var(ds, name, "f8", fill)
    v.setncatts(attrs | {"coverage_content_type": "coordinate"})


def _data_var(ds: Any, var: Variable, instruments: dict[str, str]) -> None:
    dtype = np.dtype(dtype_of(var.value_type))
    fill = dtype.type(np.nan) if dtype.kind == "f" else _INT_FILL[dtype]
    v = _obs_var(ds, var.name, dtype, fill)
    attrs: dict[str, Any] = {
        "long_name": var.long_name,
        "coordinates": "time lat lon alt",
        "modd_topic": var.topic,
        "coverage_content_type": "physicalMeasurement",
        "platform": "platform",
    }
    if var.sensor in instruments:
        attrs["instrument"] = instruments[var.sensor]
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


def _trajectory(ds: Any, plan: ExportPlan) -> None:
    name = plan.metadata.platform.get("id") or f"{plan.drone}-{plan.model_revision}"
    ds.createDimension("trajectory", 1)
    ds.createDimension("name_strlen", len(name.encode()))
    t = ds.createVariable("trajectory", "S1", ("trajectory", "name_strlen"))
    t.cf_role = "trajectory_id"
    t.long_name = "mission of the drone"
    t[0, :] = np.frombuffer(name.encode(), dtype="S1")


def _flag_var(ds: Any, var: Variable) -> None:
    """The aggregate QARTOD flag of ``var`` (its ancillary variable)."""
    name = f"{var.name}_qc_agg"
    v = _obs_var(ds, name, "i1", np.int8(-127))
    v.setncatts(FLAG_ATTRS | {"long_name": f"{var.long_name}: aggregate QARTOD quality flag"})
    ds[var.name].ancillary_variables = name


#: The location test's flag of each sample's position (lat, lon), their ancillary variable.
LOCATION = "location_qc_agg"


def _location_var(ds: Any) -> None:
    v = _obs_var(ds, LOCATION, "i1", np.int8(-127))
    v.setncatts(
        FLAG_ATTRS
        | {
            "long_name": "platform position (lat, lon): aggregate QARTOD location test flag",
            "coordinates": "time lat lon alt",
        }
    )
    ds["lat"].ancillary_variables = LOCATION
    ds["lon"].ancillary_variables = LOCATION


def _gts_ingest(ds: Any, plan: ExportPlan) -> None:
    """IOOS 1.2's ``gts_ingest = "true"`` on the file and on the variables of the
    metadata's ``gts_ingest`` topics (for NDBC's ingest to the GTS); a topic the model
    does not have is a PlanError, one left out by ``--topics`` is skipped. Received
    windows (no QARTOD flags: not real-time samples) are never marked."""
    topics = plan.metadata.gts_ingest if plan.source != "received" else ()
    known = plan.model_topics or tuple(plan.variables)
    unknown = [t for t in topics if t not in known]
    if unknown:
        source = plan.metadata.source or "dataset metadata"
        raise PlanError(f"{source}: gts_ingest: {unknown[0]} is not a topic of the model")
    chosen = [plan.variables[t] for t in topics if t in plan.variables]
    if not chosen:
        return
    ds.gts_ingest = "true"
    for var in chosen:
        ds[var.name].gts_ingest = "true"


#: The historical mark of a received window (``--received``): 0 live, 1 backfilled.
HISTORICAL = "backfilled"
HISTORICAL_ATTRS: dict[str, Any] = {
    "long_name": "how the base station received the window: live, or backfilled (historical: "
    "recomputed from the drone's archive after the link missed it, delivered late)",
    "flag_values": np.array([0, 1], dtype=np.int8),
    "flag_meanings": "live backfilled",
    "coverage_content_type": "auxiliaryInformation",
    "coordinates": "time lat lon alt",
}


#: The mark of a resampled period of received windows.
WIDE_HISTORICAL = (
    "whether a backfilled window (historical: recomputed from the drone's archive after the "
    "link missed it, delivered late) went into the period's mean: 1 yes, 0 live windows only"
)


def _historical_var(ds: Any, plan: ExportPlan) -> None:
    """The ``backfilled`` flag of every received window (an ancillary variable of each)."""
    v = _obs_var(ds, HISTORICAL, "i1", np.int8(-127))
    v.setncatts(HISTORICAL_ATTRS)
    for var in plan.variables.values():
        old = getattr(ds[var.name], "ancillary_variables", "")
        ds[var.name].ancillary_variables = f"{old} {HISTORICAL}".strip()


def create(
    path: Path, plan: ExportPlan, variables: list[Variable], flagged: set[str] | None = None
) -> Any:
    """The file with its dimensions and variables, no observation yet."""
    import netCDF4

    ds = netCDF4.Dataset(path, "w", format="NETCDF4")
    ds.setncatts(global_attributes(plan))
    _trajectory(ds, plan)
    ds.createDimension("obs", None)
    for kind in ("time", "lat", "lon", "alt"):
        _coord(ds, kind, kind)
    instruments = instrument_variables(ds, plan)
    platform_variable(ds, plan)
    for var in variables:
        _data_var(ds, var, instruments)
        if flagged and var.topic in flagged:
            _flag_var(ds, var)
    return ds


def _second_time(ds: Any, plan: ExportPlan) -> None:
    """The clock not on the axis (an auxiliary variable: CF allows one time axis)."""
    v = _obs_var(ds, plan.other_clock, "f8", np.nan)
    what = (
        "the PubBroker's receive time of the sample"
        if plan.clock == "instrument"
        else "the instrument's time of the sample (sensors declaring clock = instrument)"
    )
    v.setncatts(
        {
            "units": TIME_UNITS,
            "standard_name": "time",
            "calendar": "standard",
            "long_name": what,
            "units_metadata": "leap_seconds: none",
            "coverage_content_type": "auxiliaryInformation",
        }
    )
    ds["time"].long_name = (
        "time of the sample: the instrument's where its sensor declares clock = instrument, "
        "else the PubBroker's receive time"
        if plan.clock == "instrument"
        else "time of the sample: the PubBroker's receive time"
    )


class NetcdfSink:
    """The samples, one observation each (rows appended as the archive is read)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.ds: Any = None
        self.rows = 0
        self.plan_other = ""

    def open(self, plan: ExportPlan, track: Track | None) -> None:
        self.ds = create(self.path, plan, list(plan.variables.values()), set(qc_config(plan)))
        self.plan_other = plan.other_clock
        if plan.two_clocks:
            _second_time(self.ds, plan)
        if plan.source == "received":
            _historical_var(self.ds, plan)
        if location_config(plan) is not None:
            _location_var(self.ds)
        _gts_ingest(self.ds, plan)

    def write(
        self,
        var: Variable,
        time_ns: np.ndarray,
        value: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        other: np.ndarray | None = None,
        qc: np.ndarray | None = None,
        historical: np.ndarray | None = None,
        location: np.ndarray | None = None,
    ) -> None:
        sl = slice(self.rows, self.rows + len(time_ns))
        if historical is not None:
            self.ds[HISTORICAL][0, sl] = historical.astype(np.int8)
        self.ds["time"][0, sl] = time_ns / 1e9
        if other is not None:
            self.ds[self.plan_other][0, sl] = np.where(other == NAT, np.nan, other / 1e9)
        self.ds["lat"][0, sl] = lat
        self.ds["lon"][0, sl] = lon
        if not np.isnan(alt).all():  # no altitude: its chunks stay unwritten, the fill value
            self.ds["alt"][0, sl] = alt
        self.ds[var.name][0, sl] = value
        if qc is not None:
            self.ds[f"{var.name}_qc_agg"][0, sl] = qc
        if location is not None:
            self.ds[LOCATION][0, sl] = location
        self.rows = sl.stop

    def close(self, plan: ExportPlan, summary: Summary) -> None:
        coverage(self.ds, summary, plan)
        self.ds.close()


def write_wide(path: Path, plan: ExportPlan, table: WideTable, summary: Summary) -> None:
    """The resampled form: one row per period, every topic's mean on it."""
    means = [replace(v, value_type="float64") for v in plan.variables.values()]
    ds = create(path, plan, means)
    try:
        ds.processing_level = f"resampled: mean over {table.period_s:g} s periods"
        n = len(table.time_ns)
        if n:
            ds["time"][0, :n] = table.time_ns / 1e9
            ds["lat"][0, :n], ds["lon"][0, :n] = table.lat, table.lon
            ds["alt"][0, :n] = table.alt
        for var in means:
            ds[var.name].cell_methods = f"time: mean (interval: {table.period_s:g} s)"
            if n:
                ds[var.name][0, :n] = table.columns[var.topic]
        if table.historical is not None:
            _historical_var(ds, plan)
            ds[HISTORICAL].long_name = WIDE_HISTORICAL
            if n:
                ds[HISTORICAL][0, :n] = table.historical.astype(np.int8)
        coverage(ds, summary, plan, table.period_s)
    finally:
        ds.close()
