"""What the dataset tests ask of a MoDD NetCDF, through tools we did not write:
the IOOS compliance checker (CF-1.11 and CF-1.6, ACDD-1.3, IOOS-1.2, and the
NCEI trajectory template 2.0 through cc-plugin-ncei), pocean-core's DSG readers
and cf_xarray; and the archive read with the official ``mcap`` reader."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from mcap.reader import make_reader

BIN = Path(sys.executable).parent
SUITES = ("cf:1.11", "cf:1.6", "acdd:1.3", "ioos:1.2", "ncei-trajectory:2.0")
#: compliance-checker 6.1.0, ``ioos.py`` line 1483, ``check_gts_ingest_requirements``:
#: ``Result(BaseCheck.HIGH, False,  # always fail, "NDBC/GTS Ingest Requirements", ...)``.
#: Its value is the constant ``False`` whatever the file holds: it fails on every file
#: by design, to list the variables that qualify for NDBC's ingest to the GTS
#: (https://github.com/ioos/compliance-checker/pull/811 for issue 759; unchanged on the
#: project's main branch as of d4610de, 2026-08-17; its own unit test asserts the
#: failure for a file with no ``gts_ingest`` at all; test_checker_gts.py shows it on an
#: empty file). A file does what it asks when every variable marked
#: ``gts_ingest = "true"`` is listed as qualifying and none as not (its second message).
GTS = "NDBC/GTS Ingest Requirements"


def modd_dataset(
    files: Path, model: Path, fmt: str, out: Path, metadata: Path, *more: str
) -> subprocess.CompletedProcess[str]:
    command = [str(BIN / "modd"), "dataset", str(files), *more, "--model", str(model)]
    command += ["--metadata", str(metadata), "--format", fmt, "-o", str(out)]
    return subprocess.run(command, capture_output=True, text=True, timeout=120)


def cc_results(path: Path, out: Path, suites: tuple[str, ...] = SUITES) -> dict[str, Any]:
    """The IOOS compliance checker's JSON report, per suite."""
    tests = [a for suite in suites for a in ("--test", suite)]
    subprocess.run(
        [str(BIN / "compliance-checker"), *tests, "-f", "json", "-o", str(out), str(path)],
        capture_output=True,
        timeout=300,
    )
    results: dict[str, Any] = json.loads(out.read_text())
    return results


def _failed(res: dict[str, Any], level: str) -> list[tuple[str, Any]]:
    return [(r["name"], r["msgs"]) for r in res[level] if r["value"][0] != r["value"][1]]


def assert_compliant(path: Path, out: Path, unnamed: set[str]) -> None:
    """0 high-priority failures in every suite, but for what no file can pass:"""
    results = cc_results(path, out)
    assert set(results) == set(SUITES)
    failed = {suite: _failed(res, "high_priorities") for suite, res in results.items()}
    # CF: nothing at any level (the file claims both versions in Conventions)
    for cf in ("cf:1.11", "cf:1.6"):
        assert failed[cf] == [], failed[cf]
        assert _failed(results[cf], "medium_priorities") == [], cf
    # ACDD rates standard_name "highly recommended": only a quantity the CF table has
    # no name for (the demo's accelerometer: a platform's linear acceleration) may lack one.
    missing = {
        re.sub(r'.*variable "(\w+)".*', r"\1", name): msgs for name, msgs in failed["acdd:1.3"]
    }
    assert set(missing) <= unnamed, missing
    assert all(m == ["standard_name"] for m in missing.values()), missing
    # IOOS: only the GTS listing (see GTS), with no variable that fails to qualify.
    assert [name for name, _ in failed["ioos:1.2"]] == [GTS], failed["ioos:1.2"]
    (msgs,) = [m for name, m in failed["ioos:1.2"]]
    assert len(msgs) == 1 and "did not qualify" not in msgs[0], msgs
    listed = {n.strip() for n in msgs[0].split(":", 1)[1].split(",") if n.strip()}
    assert listed == gts_marked(path), (msgs, gts_marked(path))
    assert failed["ncei-trajectory:2.0"] == [], failed["ncei-trajectory:2.0"]


def gts_marked(path: Path) -> set[str]:
    """The variables marked for NDBC/GTS ingest (``gts_ingest = "true"``)."""
    import netCDF4

    with netCDF4.Dataset(path) as ds:
        names = {v.name for v in ds.get_variables_by_attributes(gts_ingest="true")}
        assert (getattr(ds, "gts_ingest", None) == "true") == bool(names)
    return names


def dsg_readers(path: Path, axes: dict[str, list[str]]) -> None:
    """pocean-core recognises the trajectory; cf_xarray finds its axes and its id."""
    import cf_xarray  # noqa: F401  (registers the .cf accessor)
    import xarray as xr
    from pocean.cf import CFDataset
    from pocean.dsg import IncompleteMultidimensionalTrajectory as IMT
    from pocean.utils import all_subclasses

    with CFDataset(str(path)) as nc:  # every DSG reader of pocean asked: only one claims it
        claims = [k for k in all_subclasses(CFDataset) if hasattr(k, "is_mine") and k.is_mine(nc)]
    assert claims == [IMT], claims
    with CFDataset.load(str(path)) as nc:
        assert isinstance(nc, IMT)
        with warnings.catch_warnings():  # pocean casts numpy's masked fill to datetime
            warnings.simplefilter("ignore", RuntimeWarning)
            frame = nc.to_dataframe()
        # pocean keeps the rows of variables with a standard name
        assert 0 < len(frame) <= nc.dimensions["obs"].size
    with xr.open_dataset(path) as ds:
        assert ds.cf.cf_roles == {"trajectory_id": ["trajectory"]}
        assert ds.cf.axes == axes


def official(folder: Path) -> dict[str, list[tuple[int, Any]]]:
    """(log time, value) per topic, read by the official ``mcap`` reader."""
    out: dict[str, list[tuple[int, Any]]] = {}
    for path in sorted(folder.glob("*.mcap")):
        with path.open("rb") as f:
            for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
                out.setdefault(ch.topic, []).append((m.log_time, json.loads(m.data)["value"]))
    return out


def official_windows(records: Path) -> dict[str, list[tuple[int, float]]]:
    """(window end, value) per subscriber of the base-station record (official reader)."""
    truth: dict[str, list[tuple[int, float]]] = {}
    for path in sorted(records.rglob("*.mcap")):
        with path.open("rb") as f:
            for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
                d = json.loads(m.data)
                v = float("nan") if d["value"] is None else float(d["value"])
                truth.setdefault(ch.topic.rsplit("/", 1)[1], []).append((d["end_ns"], v))
    return truth


def nc_values(ds: Any, name: str) -> np.ndarray:
    """A variable's values in a MoDD NetCDF (xarray, CF decoding): the rows where it
    is not the fill value (a row is one sample of one variable)."""
    values = np.asarray(ds[name].values[0])
    return np.asarray(values[~np.isnan(values)])


def nc_times(ds: Any, name: str) -> np.ndarray:
    times = np.asarray(ds["time"].values[0]).astype("datetime64[ns]").astype("int64")
    return np.asarray(times[~np.isnan(ds[name].values[0])])


def assert_location_flags(ds: Any, table: Any) -> None:
    """The location test's flags of every sample's position, NetCDF (``ds``, read with
    ``mask_and_scale=False``) and Parquet (``table``, pandas), are ``ioos_qc``'s
    ``location_test`` run here on the positions the files carry."""
    from ioos_qc import qartod

    assert ds["lat"].attrs["ancillary_variables"] == "location_qc_agg"
    lat, lon = ds["lat"].values[0], ds["lon"].values[0]
    rows = ds["location_qc_agg"].values[0] != -127
    want = np.asarray(qartod.location_test(lon=lon[rows], lat=lat[rows]), dtype=np.uint8)
    assert ds["location_qc_agg"].values[0][rows].tolist() == want.tolist()
    lat, lon = table["lat"].to_numpy(np.float64), table["lon"].to_numpy(np.float64)
    want = np.asarray(qartod.location_test(lon=lon, lat=lat), dtype=np.uint8)
    assert table["location_qc_agg"].tolist() == want.tolist()
    assert 1 in want
