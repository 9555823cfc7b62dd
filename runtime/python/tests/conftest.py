"""Fixtures of the runtime's tests: ``dataset_valid``, what a dataset file of
each format must be, judged by libraries MoDD did not write (pocean-core's
DSG readers and xarray for NetCDF, pyarrow and shapely for Parquet and
GeoParquet, shapely for GeoJSON, ElementTree for GPX)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

GPX = "{http://www.topografix.com/GPX/1/1}"
MODD_GPX = "https://modd.dev/schema/gpx/1"


def _netcdf(path: Path) -> int:
    import xarray as xr
    from pocean.dsg import IncompleteMultidimensionalTrajectory as IMT

    with IMT(path) as nc:
        assert IMT.is_mine(nc, strict=True)
    with xr.open_dataset(path) as ds:
        assert ds.attrs["featureType"] == "trajectory" and ds.sizes["trajectory"] == 1
        assert ds["trajectory"].attrs["cf_role"] == "trajectory_id"
        assert ds["trajectory"].values[0]  # a name, not an empty string
        for name, var in ds.data_vars.items():
            if "modd_topic" in var.attrs:
                assert var.dims == ("trajectory", "obs"), name
        return int(ds.sizes["obs"])


def _parquet(path: Path) -> int:
    import pyarrow.parquet as pq
    import shapely

    table = pq.read_table(path)
    meta = table.schema.metadata
    geo = json.loads(meta[b"geo"])
    assert geo["primary_column"] == "geometry" and geo["columns"]["geometry"]["encoding"] == "WKB"
    modd = json.loads(meta[b"modd"])
    assert modd["model_revision"] and all("units" in t for t in modd["topics"].values())
    geoms = table["geometry"].to_pylist()
    points = shapely.from_wkb([g for g in geoms if g is not None])
    lon = np.array(table["lon"].to_pylist(), dtype=float)
    placed = np.isfinite(lon)
    assert len(points) == placed.sum()
    assert np.allclose(shapely.get_x(points), lon[placed])
    return int(table.num_rows)


def _csv(path: Path) -> int:
    lines = path.read_text().splitlines()
    body = lines[1:]
    assert all(",nan" not in row.lower() and '"nan"' not in row.lower() for row in body)
    assert all("T" in row.split(",")[0] and row.split(",")[0].endswith('Z"') for row in body)
    return len(body)


def _geojson(path: Path) -> int:
    import shapely.geometry

    doc = json.loads(path.read_text())
    assert doc["type"] == "FeatureCollection"
    for f in doc["features"]:
        geom = shapely.geometry.shape(f["geometry"])  # refuses a LineString of one position
        assert geom.is_valid
    points = [f for f in doc["features"] if "time" in f["properties"]]
    if len(points) == 1:
        assert doc["features"][0]["geometry"]["type"] == "Point"
    if len(points) >= 2:
        assert doc["features"][0]["geometry"]["type"] == "LineString"
    return len(points)


def _gpx(path: Path) -> int:
    root = ET.parse(path).getroot()
    points = root.findall(f".//{GPX}trkpt")
    for pt in points:
        ext = pt.find(f"{GPX}extensions")
        assert ext is not None
        for value in ext:
            assert value.tag.startswith("{" + MODD_GPX + "}") and value.get("unit") is not None
    return len(points)


CHECKS: dict[str, Callable[[Path], int]] = {
    "netcdf": _netcdf,
    "parquet": _parquet,
    "csv": _csv,
    "geojson": _geojson,
    "gpx": _gpx,
}


@pytest.fixture
def dataset_valid() -> Callable[[str, Path], int]:
    """``check(fmt, path)``: asserts the file is a valid dataset of ``fmt``;
    returns its rows (NetCDF observations, table rows, track points)."""

    def check(fmt: str, path: Path) -> int:
        return CHECKS[fmt](path)

    return check
