"""A real track to a dataset a data manager accepts (issue 40): a sailing
yacht's chartplotter NMEA bus (B&G Zeus² 9 on the IJsselmeer, gpsd's capture
tests/sensors/captures/bundg_zeus_9.log: GNSS, echo sounder, heel and trim)
replayed through a pseudo-terminal into ``modd up`` (modd-sensors reads it with
``clock = instrument``; the PubBroker archives it, the SubBroker records its
subscriptions), ten times faster than it was sent. Then ``modd dataset``, per
option (plain, ``--time instrument``, ``--resample``, ``--received``) and per
format (NetCDF, Parquet, CSV): the NetCDF passes the IOOS compliance checker
(CF-1.11, CF-1.6, ACDD-1.3, IOOS-1.2, NCEI trajectory 2.0) with no
high-priority failure, pocean-core and cf_xarray read it as a trajectory, and
the three formats hold the same values, those of the archive read by the
official ``mcap`` reader (the resampled means recomputed here by pandas)."""

from __future__ import annotations

import datetime
import json
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd  # type: ignore[import-untyped]
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pynmea2  # type: ignore[import-untyped]
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
from devices import PtyDevice, nmea, wait_until
from mcap.reader import make_reader
from modd.ports import free_port

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
CAPTURE = ROOT / "tests" / "sensors" / "captures" / "bundg_zeus_9.log"
METADATA = Path(__file__).with_name("yacht.yaml")
PACE = 10.0  # times faster than the chartplotter sent it (~146 s of sailing)
PERIOD_S = 2
MODEL = """
Drone yacht "Sailing yacht, B&G chartplotter" {{
    Sensors {{
        Sensor bus "B&G Zeus2 9 chartplotter, NMEA 0183 output" kind nmea on "{dev}"
                {{ baud = 4800; clock = instrument; }} measures {{
            lat(degree_north, float64) from sentence GGA.lat
                {{ standardName = latitude; longName = "GNSS latitude"; }};
            lon(degree_east, float64) from sentence GGA.lon
                {{ standardName = longitude; longName = "GNSS longitude"; }};
            sog(METER_PER_SECOND) from sentence RMC.speed_knots scale 0.514444
                {{ standardName = platform_speed_wrt_ground; longName = "Speed over ground"; }};
            cog("degree") from sentence VTG.course_true
                {{ standardName = platform_course; longName = "Course over ground"; }};
            depth(METER) from sentence DPT.depth offset 0.4
                {{ standardName = sea_floor_depth_below_sea_surface;
                   longName = "Water depth: DPT depth plus its 0.4 m transducer offset"; }};
            heel("degree") from sentence XDR.f6
                {{ standardName = platform_roll; longName = "Heel (XDR HEEL)"; }};
            trim("degree") from sentence XDR.f10
                {{ standardName = platform_pitch; longName = "Trim (XDR TRIM)"; }};
        }}
    }}
    Position {{ latitude = "yacht.bus.lat"; longitude = "yacht.bus.lon"; maxGap = 5; }}
}}
PubBroker onboard("127.0.0.1":{port}, "/tmp/unused");
SubBroker base("127.0.0.1":{port2}, "/tmp/unused");
Publishers {{
    Publisher bus(1.0, "yacht.bus.lat", "yacht.bus.lon", "yacht.bus.sog", "yacht.bus.cog",
                  "yacht.bus.depth", "yacht.bus.heel", "yacht.bus.trim");
}}
Subscriptions {{
    Subscriber track_lat("yacht.bus.lat", 1.0, LAST);
    Subscriber track_lon("yacht.bus.lon", 1.0, LAST);
    Subscriber depth_mean("yacht.bus.depth", 1.0, AVERAGE);
    Subscriber heel_max("yacht.bus.heel", 1.0, MAX);
    Subscriber speed("yacht.bus.sog", 1.0, AVERAGE);
}}
"""
AXES = {"X": ["lon"], "Y": ["lat"], "Z": ["alt"], "T": ["time"]}
OPTIONS = {
    "plain": (),
    "instrument": ("--time", "instrument"),
    "resample": ("--resample", str(PERIOD_S)),
    "received": ("--received",),
}


#: Where each sentence type states its UTC time of day (field number).
TIMED = {"GGA": 1, "GLL": 5, "RMC": 1, "ZDA": 1}
SAILED = datetime.datetime(2018, 8, 20, tzinfo=datetime.UTC)  # the capture's date
FIRST_FIX = SAILED.replace(hour=9, minute=47, second=36)


def _lines() -> list[bytes]:
    text = CAPTURE.read_text(encoding="utf-8")
    return [f"{ln.strip()}\r\n".encode() for ln in text.splitlines() if ln.startswith("$")]


def _retimed(line: bytes, shift: datetime.timedelta) -> bytes:
    """The sentence with its time and date moved by ``shift`` (its checksum redone):
    the PubBroker refuses a sample stamped more than an hour before its clock, and
    the GNSS states the time, so the 2018 voyage is sailed again today. Values are
    untouched."""
    body = line.decode().strip()[1:].split("*")[0]
    f = body.split(",")
    field = TIMED.get(f[0][2:])
    if field is None or not f[field]:
        return line
    clock = datetime.datetime.strptime(f[field][:6], "%H%M%S").time()
    at = datetime.datetime.combine(SAILED.date(), clock, datetime.UTC) + shift
    f[field] = at.strftime("%H%M%S") + f[field][6:]
    if f[0].endswith("RMC"):
        f[9] = at.strftime("%d%m%y")
    if f[0].endswith("ZDA"):
        f[2:5] = [at.strftime("%d"), at.strftime("%m"), at.strftime("%Y")]
    return bytes(nmea(",".join(f)))


def _values(run: Path) -> int:
    try:
        return int(json.loads((run / "sensors.json").read_text())["sensors"]["bus"]["values"])
    except (FileNotFoundError, ValueError, KeyError):
        return -1


def _replay(device: PtyDevice, run: Path) -> None:
    """The capture at PACE times its pace (one second of sentences per ZDA), its
    last fix stamped a few seconds before now (the instrument's clock)."""
    second = 1.0 / PACE
    span = len([ln for ln in _lines() if ln.startswith(b"$GPZDA")]) * second
    now = datetime.datetime.now(datetime.UTC)
    shift = now + datetime.timedelta(seconds=span - 160) - FIRST_FIX
    for line in _lines():
        device.write(_retimed(line, shift))
        if line.startswith(b"$GPZDA"):
            time.sleep(second)
    # every sample handed on, then the last windows recorded at the base station
    last = -2
    while (n := _values(run)) != last:
        last = n
        time.sleep(1.0)
    time.sleep(2.5)


@pytest.fixture(scope="module")
def voyage(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(run folder, model): the capture sailed through ``modd up``."""
    tmp = tmp_path_factory.mktemp("voyage")
    device = PtyDevice(tmp / "chartplotter")
    model = tmp / "yacht.modd"
    model.write_text(MODEL.format(dev=device.path, port=free_port(), port2=free_port()))
    run = tmp / "run"
    command = [str(BIN / "modd"), "up", str(model), "--workdir", str(run)]
    command += ["--zenoh-listen", f"tcp/127.0.0.1:{free_port()}"]
    up = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        log = run / "logs" / "subbroker.log"
        wait_until(
            lambda: log.exists() and "config 1 running" in log.read_text(errors="replace"),
            60,
            "the SubBroker runs the model",
        )
        wait_until(lambda: _values(run) >= 0, 30, "modd-sensors opened the chartplotter")
        _replay(device, run)
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
        device.close()
    assert up.returncode == 0, out
    return run, model


def test_every_fix_of_the_capture_is_archived(voyage: tuple[Path, Path]) -> None:
    """The archive is the capture's (pynmea2 reads the GGA positions): the oracle
    the exports are compared with is complete."""
    fixes = [pynmea2.parse(ln.decode().strip()) for ln in _lines() if ln.startswith(b"$GPGGA")]
    archive = official(voyage[0] / "archive")
    got = [v for _, v in archive["yacht.bus.lat"]]
    assert got == [pytest.approx(f.latitude, abs=1e-12) for f in fixes if f.gps_qual]
    names = ("lat", "lon", "sog", "cog", "depth", "heel", "trim")
    assert set(archive) == {f"yacht.bus.{v}" for v in names}


def _export(voyage: tuple[Path, Path], option: str, out: Path) -> dict[str, Path]:
    run, model = voyage
    source = run / "records" / "yacht" if option == "received" else run / "archive"
    paths = {}
    for fmt, suffix in (("netcdf", "nc"), ("parquet", "parquet"), ("csv", "csv")):
        paths[fmt] = out / f"yacht-{option}.{suffix}"
        done = modd_dataset(source, model, fmt, paths[fmt], METADATA, *OPTIONS[option])
        assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
        assert "no CF standard name" not in done.stderr, done.stderr
    return paths


def _tables(paths: dict[str, Path]) -> tuple[pd.DataFrame, pd.DataFrame]:
    return pq.read_table(paths["parquet"]).to_pandas(), pcsv.read_csv(paths["csv"]).to_pandas()


def _name(topic: str) -> str:
    return topic.split(".", 1)[1].replace(".", "_")


def _samples_agree(ds: Any, paths: dict[str, Path], folder: Path, clock: str) -> None:
    """Long form: every sample of the archive, in every format, at its time."""
    truth = _clocked(folder, clock)
    table, csv = _tables(paths)
    assert len(table) == len(csv) == sum(len(v) for v in truth.values())
    for topic, samples in truth.items():
        rows = table[table["topic"] == topic]
        want = [float(v) for _, v in samples]
        assert rows["value"].tolist() == want, topic
        assert csv[csv["topic"] == topic]["value"].tolist() == want, topic
        assert rows["time"].astype("int64").tolist() == [t for t, _ in samples], topic
        name = _name(topic)
        stored = np.array(want, ds[name].encoding["dtype"]).astype(np.float64)
        assert np.array_equal(nc_values(ds, name), stored), topic
        assert np.abs(nc_times(ds, name) - [t for t, _ in samples]).max() < 1000, topic
    times = [t for samples in truth.values() for t, _ in samples]  # ACDD's coverage
    assert abs(pd.Timestamp(ds.attrs["time_coverage_start"]).value - min(times)) < 1000
    assert abs(pd.Timestamp(ds.attrs["time_coverage_end"]).value - max(times)) < 1000


def _clocked(folder: Path, clock: str) -> dict[str, list[tuple[int, Any]]]:
    """The official reader's samples on the export's axis: log time (the PubBroker's
    receive time) or publish time (the instrument's, clock = instrument)."""
    if clock == "receive":
        return official(folder)
    out: dict[str, list[tuple[int, Any]]] = {}
    for path in sorted(folder.glob("*.mcap")):
        with path.open("rb") as f:
            for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
                out.setdefault(ch.topic, []).append((m.publish_time, json.loads(m.data)["value"]))
    return out


def _means_agree(ds: Any, paths: dict[str, Path], folder: Path) -> None:
    """Wide form: each period's mean, recomputed by pandas from the official reader."""
    period = PERIOD_S * 10**9
    means = {}
    for topic, samples in official(folder).items():
        frame = pd.DataFrame(samples, columns=["t", "v"]).astype({"v": float})
        means[_name(topic)] = frame.groupby(frame["t"] // period)["v"].mean()
    wide = pd.DataFrame(means).sort_index()
    table, csv = _tables(paths)
    centres = wide.index.to_numpy() * period + period // 2
    assert table["time"].astype("int64").tolist() == centres.tolist()
    for name in means:
        want = wide[name].to_numpy()
        assert np.allclose(table[name], want, rtol=1e-12, equal_nan=True), name
        assert np.allclose(csv[name], want, rtol=1e-12, equal_nan=True), name
        assert np.allclose(ds[name].values[0], want, rtol=1e-12, equal_nan=True), name


def _windows_agree(ds: Any, paths: dict[str, Path], records: Path) -> None:
    """Received windows: each window the SubBroker recorded, at its end."""
    truth = official_windows(records)
    assert set(truth) == {"track_lat", "track_lon", "depth_mean", "heel_max", "speed"}
    table, csv = _tables(paths)
    for name, windows in truth.items():
        want = [v for _, v in windows]
        rows = table[table["topic"] == name]
        assert rows["time"].astype("int64").tolist() == [t for t, _ in windows], name
        assert np.allclose(rows["value"], want, equal_nan=True), name
        assert np.allclose(csv[csv["topic"] == name]["value"], want, equal_nan=True), name
        assert np.array_equal(nc_values(ds, name), [v for v in want if not np.isnan(v)]), name


@pytest.mark.parametrize("option", list(OPTIONS))
def test_each_option_passes_the_checkers_and_formats_agree(
    voyage: tuple[Path, Path], option: str, tmp_path: Path
) -> None:
    import xarray as xr

    paths = _export(voyage, option, tmp_path)
    assert_compliant(paths["netcdf"], tmp_path / "cc.json", set())
    samples = option not in ("resample", "received")  # flagged samples: marked for the GTS
    assert gts_marked(paths["netcdf"]) == ({"bus_depth"} if samples else set())
    dsg_readers(paths["netcdf"], AXES)
    run = voyage[0]
    with xr.open_dataset(paths["netcdf"]) as ds:
        if option == "received":
            _windows_agree(ds, paths, run / "records")
        elif option == "resample":
            _means_agree(ds, paths, run / "archive")
        else:
            clock = "instrument" if option == "instrument" else "receive"
            _samples_agree(ds, paths, run / "archive", clock)


def test_quality_flags_are_ioos_qcs_on_the_instruments_clock(
    voyage: tuple[Path, Path], tmp_path: Path
) -> None:
    """yacht.yaml's four QARTOD tests per topic, run here by ``ioos_qc`` itself on the
    official reader's samples at the instrument's times (1 Hz: the timed tests run),
    give the export's flags (the export runs two of them vectorised: qcfast.py)."""
    import xarray as xr
    import yaml
    from ioos_qc import qartod

    paths = _export(voyage, "instrument", tmp_path)
    config = yaml.safe_load(METADATA.read_text())["qc"]
    truth = _clocked(voyage[0] / "archive", "instrument")
    table = pq.read_table(paths["parquet"]).to_pandas()
    seen: set[int] = set()
    with xr.open_dataset(paths["netcdf"], mask_and_scale=False) as ds:
        for topic, tests in config.items():
            times = np.array([t for t, _ in truth[topic]]).astype("datetime64[ns]")
            v = np.ma.masked_invalid(np.array([v for _, v in truth[topic]], np.float64))
            flags = [
                getattr(qartod, k)(inp=v, tinp=times, **p)
                if k in ("rate_of_change_test", "flat_line_test")
                else getattr(qartod, k)(inp=v, **p)
                for k, p in tests.items()
            ]
            want = qartod.qartod_compare(flags).tolist()
            name = _name(topic)
            got = ds[f"{name}_qc_agg"].values[0]
            assert got[got != -127].tolist() == want, topic
            assert table[table["topic"] == topic]["qc_agg"].tolist() == want, topic
            seen |= set(want)
        assert_location_flags(ds, table)
    assert seen > {1}, seen  # the real track is not all PASS


@pytest.mark.parametrize("option", list(OPTIONS))
def test_each_option_gives_the_same_track_in_geojson_and_gpx(
    voyage: tuple[Path, Path], option: str, tmp_path: Path
) -> None:
    """The track formats take every option too: valid GeoJSON (lon, lat) and GPX,
    the same points in both, all within the capture's own fixes (pynmea2)."""
    import xml.etree.ElementTree as ET

    run, model = voyage
    source = run / "records" / "yacht" if option == "received" else run / "archive"
    out = {}
    for fmt in ("geojson", "gpx"):
        out[fmt] = tmp_path / f"yacht.{fmt}"
        done = modd_dataset(source, model, fmt, out[fmt], METADATA, *OPTIONS[option])
        assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    features = json.loads(out["geojson"].read_text())["features"]
    assert features[0]["geometry"]["type"] == "LineString"
    line = features[0]["geometry"]["coordinates"]
    gpx = "{http://www.topografix.com/GPX/1/1}"
    points = ET.parse(out["gpx"]).getroot().findall(f".//{gpx}trkpt")
    assert len(points) == len(features) - 1 == len(line) >= 2
    assert [[float(p.get("lon", "")), float(p.get("lat", ""))] for p in points] == line
    fixes = [pynmea2.parse(ln.decode().strip()) for ln in _lines() if ln.startswith(b"$GPGGA")]
    lats, lons = [f.latitude for f in fixes], [f.longitude for f in fixes]
    for lon, lat in line:
        assert min(lats) <= lat <= max(lats) and min(lons) <= lon <= max(lons), (lat, lon)
