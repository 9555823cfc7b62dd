"""From mission to dataset, for real: `modd up metamodel/examples/demo.modd
--simulate` writes an archive; `modd dataset` exports it in the five formats,
plain, resampled and received, with a data manager's metadata (dataset.yaml
here). Checked against tools we did not write: the IOOS compliance checker
(CF-1.11 and CF-1.6, ACDD-1.3, IOOS-1.2, and the NCEI trajectory template
through cc-plugin-ncei), pocean-core's DSG readers, xarray's and cf_xarray's CF
decoding, the official `mcap` reader (every value), and the simulator's own
track (every position)."""

from __future__ import annotations

import contextlib
import json
import math
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from checkers import (
    assert_compliant,
    assert_location_flags,
    dsg_readers,
    gts_marked,
    modd_dataset,
    nc_times,
    nc_values,
    official,
    official_windows,
)
from mcap.reader import make_reader
from modd.ports import free_port
from modd.sim.track import survey_pose

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
METADATA = Path(__file__).with_name("dataset.yaml")
FORMATS = {"netcdf": "nc", "parquet": "parquet", "csv": "csv", "geojson": "geojson", "gpx": "gpx"}
#: How far an interpolated position may be from the simulator's truth: the boat
#: moves at 2 m/s, fixes come every 0.2 s, and a fix is stamped on board after
#: crossing UDP, the bridge and the ingress (tens of ms, up to ~1 s on a loaded
#: machine): docs/user-guide/datasets.md says the same.
TOLERANCE_M = 5.0


def _wait(path: Path, text: str, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if path.exists() and text in path.read_text(errors="replace"):
            return
        time.sleep(0.2)
    raise AssertionError(f"{text!r} never appeared in {path}")


@pytest.fixture(scope="module")
def mission(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, float]:
    """(archive folder, model, track start): ~12 s of the demo, simulated."""
    tmp = tmp_path_factory.mktemp("mission")
    model = tmp / "demo.modd"
    text = (ROOT / "metamodel" / "examples" / "demo.modd").read_text()
    text = text.replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}')
    # the GNSS stamps its samples with its own clock (its ZDA/RMC time): both clocks
    text = text.replace(
        '"/dev/ttyACM0" { baud = 9600; }', '"/dev/ttyACM0" { baud = 9600; clock = instrument; }'
    )
    assert "clock = instrument" in text
    model.write_text(text)
    run = tmp / "run"
    up = subprocess.Popen(
        [
            str(BIN / "modd"),
            "up",
            str(model),
            "--simulate",
            "--workdir",
            str(run),
            "--zenoh-listen",
            f"tcp/127.0.0.1:{free_port()}",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        _wait(run / "logs" / "subbroker.log", "config 1 running", 60)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and _archived_fixes(run / "archive") < 40:
            time.sleep(1.0)
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
    assert up.returncode == 0, out
    start = re.search(r"track started at ([0-9.]+)", (run / "logs" / "simulator.log").read_text())
    assert start, "the simulator says when its track started"
    return run / "archive", model, float(start.group(1))


def _archived_fixes(folder: Path) -> int:
    """Latitude fixes flushed so far (only to know when to stop: not an oracle)."""
    from modd.dataset.mcapread import ArchiveError, read_file

    n = 0
    for f in folder.glob("*.mcap"):
        with contextlib.suppress(ArchiveError):  # a file being written
            n += sum(len(b.time_ns) for b in read_file(f, only={"usv.autopilot.latitude"}))
    return n


def _modd_dataset(
    files: Path, model: Path, fmt: str, out: Path, *more: str
) -> subprocess.CompletedProcess[str]:
    return modd_dataset(files, model, fmt, out, METADATA, *more)


@pytest.fixture(scope="module")
def exports(
    mission: tuple[Path, Path, float], tmp_path_factory: pytest.TempPathFactory
) -> dict[str, Path]:
    archive, model, _ = mission
    out = tmp_path_factory.mktemp("exports")
    paths = {}
    for fmt, suffix in FORMATS.items():
        paths[fmt] = out / f"demo.{suffix}"
        done = _modd_dataset(archive, model, fmt, paths[fmt])
        assert done.returncode == 0, done.stderr
        assert "Traceback" not in done.stderr
        if fmt == "netcdf":  # the only variables without a CF standard name, said
            unnamed = ", ".join(f"usv.accelerometer.accel_{a}" for a in "xyz")
            assert f"note: no CF standard name for {unnamed} (" in done.stderr, done.stderr
    return paths


AXES = {"X": ["lon"], "Y": ["lat"], "Z": ["alt"], "T": ["time"]}


ACCEL = {f"accelerometer_accel_{a}" for a in "xyz"}


def test_netcdf_passes_the_ioos_compliance_checker(
    exports: dict[str, Path], tmp_path: Path
) -> None:
    assert_compliant(exports["netcdf"], tmp_path / "cc.json", ACCEL)
    # dataset.yaml's gts_ingest: both qualify (QARTOD flag, CF standard name, units)
    assert gts_marked(exports["netcdf"]) == {"ctd_water_temperature", "sounder_depth"}
    dsg_readers(exports["netcdf"], AXES)


def test_resampled_netcdf_passes_the_checkers(
    mission: tuple[Path, Path, float], tmp_path: Path
) -> None:
    archive, model, _ = mission
    out = tmp_path / "r.nc"
    done = _modd_dataset(archive, model, "netcdf", out, "--resample", "2")
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert_compliant(out, tmp_path / "cc.json", ACCEL)
    dsg_readers(out, AXES)
    tables = {}
    for fmt in ("parquet", "csv"):
        path = tmp_path / f"r.{fmt}"
        done = _modd_dataset(archive, model, fmt, path, "--resample", "2")
        assert done.returncode == 0, done.stderr
        table = pq.read_table(path) if fmt == "parquet" else pcsv.read_csv(path)
        tables[fmt] = table.to_pandas()
    import xarray as xr

    with xr.open_dataset(out) as ds:
        for name, var in ds.data_vars.items():
            if "modd_topic" in var.attrs:
                nc = var.values[0]
                assert np.allclose(tables["parquet"][name], nc, equal_nan=True), name
                assert np.allclose(tables["csv"][name], nc, equal_nan=True, rtol=1e-15), name


@pytest.fixture(scope="module")
def received(
    mission: tuple[Path, Path, float], tmp_path_factory: pytest.TempPathFactory
) -> dict[str, Path]:
    """``modd dataset --received`` of the mission's base-station record."""
    archive, model, _ = mission
    out = tmp_path_factory.mktemp("received")
    paths = {}
    for fmt in ("netcdf", "parquet", "csv"):
        paths[fmt] = out / f"received.{FORMATS[fmt]}"
        done = _modd_dataset(
            archive.parent / "records" / "usv", model, fmt, paths[fmt], "--received"
        )
        assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
        assert "values of 14 subscribers" in done.stdout, done.stdout
    return paths


def test_the_received_windows_are_the_records(
    mission: tuple[Path, Path, float], received: dict[str, Path], tmp_path: Path
) -> None:
    """Every window the SubBroker recorded, read independently (the official
    reader), is in the export at its end; its NetCDF passes the IOOS checker."""
    import xarray as xr

    truth = official_windows(mission[0].parent / "records")
    assert len(truth) == 14 and all(len(v) >= 2 for v in truth.values())
    table = pq.read_table(received["parquet"]).to_pandas()
    csv = pcsv.read_csv(received["csv"]).to_pandas()
    with xr.open_dataset(received["netcdf"]) as ds:
        for name, windows in truth.items():
            rows = table[table["topic"] == name]
            assert rows["time"].astype("int64").tolist() == [t for t, _ in windows], name
            assert np.allclose(rows["value"], [v for _, v in windows], equal_nan=True), name
            values = csv[csv["topic"] == name]["value"].to_numpy(dtype=float)
            assert np.allclose(values, [v for _, v in windows], equal_nan=True), name
            got = nc_values(ds, name)
            assert np.array_equal(got, [v for _, v in windows if not math.isnan(v)]), name
    accel = {f"sub_{i}" for i in range(1, 8)}
    assert_compliant(received["netcdf"], tmp_path / "cc.json", accel)
    dsg_readers(received["netcdf"], AXES)


def test_every_value_is_the_archives(
    mission: tuple[Path, Path, float], exports: dict[str, Path]
) -> None:
    import xarray as xr

    truth = official(mission[0])
    table = pq.read_table(exports["parquet"]).to_pandas()
    csv = pcsv.read_csv(exports["csv"]).to_pandas()
    assert len(table) == len(csv) == sum(len(v) for v in truth.values())
    with xr.open_dataset(exports["netcdf"]) as ds:  # CF decoding: times become datetimes
        for topic, samples in truth.items():
            rows = table[table["topic"] == topic]
            assert rows["value"].tolist() == [float(v) for _, v in samples], topic
            assert csv[csv["topic"] == topic]["value"].tolist() == rows["value"].tolist()
            name = topic.split(".", 1)[1].replace(".", "_")
            stored = np.float64 if isinstance(samples[0][1], int) else ds[name].encoding["dtype"]
            want = np.array([v for _, v in samples], stored).astype(np.float64)
            assert np.array_equal(nc_values(ds, name), want), topic
            times = nc_times(ds, name)
            assert np.abs(times - [t for t, _ in samples]).max() < 1000, topic


def test_quality_flags_are_ioos_qcs_on_the_archive(
    mission: tuple[Path, Path, float], exports: dict[str, Path]
) -> None:
    """dataset.yaml's qc section, run here by ioos_qc on the official reader's samples
    (the CTD samples at 2 Hz: the timed tests are left out, as the export's notes say)."""
    import xarray as xr
    import yaml
    from ioos_qc import qartod

    config = yaml.safe_load(METADATA.read_text())["qc"]
    truth = official(mission[0])
    table = pq.read_table(exports["parquet"]).to_pandas()
    with xr.open_dataset(exports["netcdf"], mask_and_scale=False) as ds:
        for topic in ("usv.ctd.water_temperature", "usv.sounder.depth"):
            v = np.ma.masked_invalid(np.array([v for _, v in truth[topic]], np.float64))
            tests = {
                k: p
                for k, p in config[topic].items()
                if not k.endswith(("change_test", "line_test"))
            }
            want = qartod.qartod_compare([getattr(qartod, k)(inp=v, **p) for k, p in tests.items()])
            name = topic.split(".", 1)[1].replace(".", "_")
            assert ds[name].attrs["ancillary_variables"] == f"{name}_qc_agg"
            flags = ds[f"{name}_qc_agg"].values[0]
            assert np.array_equal(flags[flags != -127], want), topic
            assert table[table["topic"] == topic]["qc_agg"].tolist() == list(want), topic
        assert "autopilot_roll_qc_agg" not in ds
        assert_location_flags(ds, table)


def test_every_position_is_the_simulators(
    mission: tuple[Path, Path, float], exports: dict[str, Path]
) -> None:
    _, _, start = mission
    table = pq.read_table(exports["parquet"]).to_pandas()
    placed = table.dropna(subset=["lat", "lon"])
    assert len(placed) > 0.9 * len(table)
    secs = placed["time"].astype("int64").to_numpy() / 1e9 - start
    worst = 0.0
    for s, lat, lon in zip(secs, placed["lat"], placed["lon"], strict=True):
        p = survey_pose(s)
        north = (lat - p.lat) * 111_320.0
        east = (lon - p.lon) * 111_320.0 * math.cos(math.radians(p.lat))
        worst = max(worst, math.hypot(north, east))
    assert worst < TOLERANCE_M, f"{worst:.2f} m"


def test_tracks_open_as_geojson_and_gpx(exports: dict[str, Path]) -> None:
    import xml.etree.ElementTree as ET

    features = json.loads(exports["geojson"].read_text())["features"]
    assert features[0]["geometry"]["type"] == "LineString" and len(features) > 5
    assert "ctd_water_temperature" in features[1]["properties"]
    pts = ET.parse(exports["gpx"]).getroot().findall(".//{http://www.topografix.com/GPX/1/1}trkpt")
    assert len(pts) == len(features) - 1
    temp = pts[0].find(".//{https://modd.dev/schema/gpx/1}ctd_water_temperature")
    assert temp is not None and temp.get("unit") == "degC"
    assert (
        exports["csv"].read_text().splitlines()[0]
        == '"time","topic","value","unit","lat","lon","alt","instrument_time","qc_agg",'
        '"location_qc_agg"'
    )


def test_the_instruments_clock_is_kept_beside_the_receive_time(
    mission: tuple[Path, Path, float], exports: dict[str, Path]
) -> None:
    """The GNSS declares clock = instrument: its samples carry the time the reader
    took from its ZDA/RMC sentences (the archive's publish time, read here by the
    official reader), the other topics none."""
    truth: dict[str, list[int]] = {}
    for path in sorted(mission[0].glob("*.mcap")):
        with path.open("rb") as f:
            for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
                truth.setdefault(ch.topic, []).append(m.publish_time)
    table = pq.read_table(exports["parquet"]).to_pandas()
    for topic in truth:
        rows = table[table["topic"] == topic]["instrument_time"]
        if topic.startswith("usv.gnss."):
            assert rows.astype("int64").tolist() == truth[topic], topic
        else:
            assert rows.isna().all(), topic


def test_the_erddap_excerpts_serve_every_variable(exports: dict[str, Path]) -> None:
    """The datasets.xml excerpts of the scientist's guide and docs/ecosystem.md are
    for this export: one dataVariable per variable on the observation axis (and the
    trajectory id), in the file's order, as ERDDAP's EDDTableFromNcCFFiles reads it."""
    import xml.etree.ElementTree as ET

    import netCDF4

    with netCDF4.Dataset(exports["netcdf"]) as ds:
        want = [n for n, v in ds.variables.items() if "obs" in v.dimensions or n == "trajectory"]
    for doc in ("docs/user-guide/datasets.md", "docs/ecosystem.md"):
        text = (ROOT / doc).read_text()
        blocks = re.findall(r"```xml\n(<dataset .*?</dataset>)\n```", text, re.S)
        assert len(blocks) == 1, doc
        root = ET.fromstring(blocks[0])
        assert root.get("type") == "EDDTableFromNcCFFiles", doc
        names = [d.findtext("sourceName") for d in root.findall("dataVariable")]
        assert names == want, doc
