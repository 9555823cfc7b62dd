"""QARTOD quality flags in ``modd dataset`` (qc.py): a spike and a stuck
value injected into a simulated CTD series are flagged in NetCDF, Parquet and
CSV, and every flag equals ``ioos_qc`` run here, directly, on the samples the
official ``mcap`` reader returns, with the same configuration."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from ioos_qc import qartod
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from modd.dataset.build import DatasetError, make_dataset
from modd.dataset.metadata import MetadataError, parse_metadata
from modd_model import load_text

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
T0, S = 1_790_000_000 * 10**9, 10**9
MODEL = """
Drone boat {
    Sensors {
        Sensor gps measures { lat(degree_north, float64); lon(degree_east, float64); }
        Sensor ctd measures {
            temp(degC, float64) { standardName = sea_water_temperature; RANGE };
            n(NONE, float64);
        }
    }
    Position { latitude = "boat.gps.lat"; longitude = "boat.gps.lon"; maxGap = 3; }
}
PubBroker("127.0.0.1":7171, "/tmp/l"); SubBroker("127.0.0.1":7272, "/tmp/c");
Publishers { Publisher p(1, "boat.gps.lat", "boat.gps.lon", "boat.ctd.temp", "boat.ctd.n"); }
Subscriptions { }
"""
Messages = list[tuple[str, int, float]]


def write_archive(path: Path, messages: Messages) -> Path:
    """An archive by the official writer, float64 channels as the contract says."""
    doc = json.loads((VECTORS / "archive_record.json").read_text())
    c = next(c for c in doc["channels"] if c["type"] == "float64")
    with path.open("wb") as f:
        w = Writer(f, chunk_size=4096, compression=CompressionType.ZSTD)
        w.start(profile="", library="test")
        sid = w.register_schema(c["schema_name"], c["schema_encoding"], c["schema_data"].encode())
        ids: dict[str, int] = {}
        for topic, t, value in messages:
            if topic not in ids:
                ids[topic] = w.register_channel(topic, c["message_encoding"], sid, c["metadata"])
            data = b'{"value":' + repr(value).encode() + b"}"
            w.add_message(ids[topic], log_time=t, data=data, publish_time=t)
        w.finish()  # type: ignore[no-untyped-call]
    return path


TEMP = "boat.ctd.temp"
SPIKE, STUCK = 55, (120, 180)  # the spike's sample, the stuck run (samples at 1 Hz)
QC: dict[str, Any] = {
    TEMP: {
        "spike_test": {"suspect_threshold": 0.5, "fail_threshold": 2},
        "rate_of_change_test": {"threshold": 5},
        "flat_line_test": {"suspect_threshold": 10, "fail_threshold": 20, "tolerance": 0.0001},
    }
}


def _model(ranged: bool = True) -> dict[str, Any]:
    # the model's declared range: the default gross range test
    text = MODEL.replace("RANGE", "validMin = 0; validMax = 30;" if ranged else "")
    result = load_text(text, "boat.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def _temp(i: int) -> float:
    if i == SPIKE:
        return 25.0  # 13 degC above its neighbours: FAIL
    if STUCK[0] <= i < STUCK[1]:
        return 13.0  # stuck for 60 s: flat line FAIL after 20 s
    return round(12 + 0.01 * i + 0.05 * float(np.sin(i)), 4)


def _mission(seconds: int = 250, hz: int = 1) -> Messages:
    out: Messages = []
    for i in range(seconds):
        t = T0 + i * S
        out += [("boat.gps.lat", t, 47.0 + 1e-4 * i), ("boat.gps.lon", t, -3.0)]
        out += [("boat.ctd.n", t, float(i))]
        out += [(TEMP, t + k * S // hz + 7, _temp(hz * i + k)) for k in range(hz)]
    out.append((TEMP, T0 + seconds * S, 31.0))  # above validMax: gross range FAIL
    return out


@pytest.fixture
def archive(tmp_path: Path) -> Path:
    return write_archive(tmp_path / "boat-0.mcap", _mission())


def _expected(path: Path) -> np.ndarray:
    """The oracle: ioos_qc on the official reader's samples, the same tests."""
    with path.open("rb") as f:
        messages = make_reader(f).iter_messages(topics=[TEMP], log_time_order=True)
        pairs = [(m.log_time, json.loads(m.data)["value"]) for _s, _c, m in messages]
    t = np.array([p[0] for p in pairs], dtype="datetime64[ns]")
    v = np.ma.masked_invalid(np.array([p[1] for p in pairs], dtype=np.float64))
    p = QC[TEMP]
    flags = [
        qartod.gross_range_test(inp=v, fail_span=[0.0, 30.0]),
        qartod.spike_test(inp=v, **p["spike_test"]),
        qartod.rate_of_change_test(inp=v, tinp=t, **p["rate_of_change_test"]),
        qartod.flat_line_test(inp=v, tinp=t, **p["flat_line_test"]),
    ]
    return np.asarray(qartod.qartod_compare(flags), dtype=np.uint8)


def _meta() -> Any:
    return parse_metadata({"qc": QC}, "dataset.yaml")


def _injected_are_flagged(flags: np.ndarray) -> None:
    assert flags[SPIKE] == 4
    assert flags[STUCK[0] + 21 : STUCK[1]].min() == 4  # stuck longer than 20 s
    assert flags[-1] == 4  # out of the declared range
    assert (flags[: SPIKE - 1] == 1).all()  # a clean start passes


def test_netcdf_flags_equal_ioos_qc_and_are_cf(archive: Path, tmp_path: Path) -> None:
    import xarray as xr

    out = tmp_path / "q.nc"
    make_dataset([archive], _model(), "netcdf", out, metadata=_meta())
    with xr.open_dataset(out, mask_and_scale=False) as ds:
        assert ds["ctd_temp"].attrs["ancillary_variables"] == "ctd_temp_qc_agg"
        flag = ds["ctd_temp_qc_agg"]
        assert flag.attrs["flag_meanings"] == "PASS NOT_EVALUATED SUSPECT FAIL MISSING"
        assert list(flag.attrs["flag_values"]) == [1, 2, 3, 4, 9]
        assert flag.attrs["standard_name"] == "aggregate_quality_flag"
        have = ds["ctd_temp"].values[0] == ds["ctd_temp"].values[0]  # not the fill value
        order = np.argsort(ds["time"].values[0][have], kind="stable")
        got = flag.values[0][have][order]
        assert "ctd_n_qc_agg" not in ds and "gps_lat_qc_agg" not in ds
    expected = _expected(archive)
    np.testing.assert_array_equal(got, expected)
    _injected_are_flagged(got)


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_table_flags_equal_ioos_qc(archive: Path, tmp_path: Path, fmt: str) -> None:
    out = tmp_path / f"q.{fmt}"
    make_dataset([archive], _model(), fmt, out, metadata=_meta())
    table = pq.read_table(out) if fmt == "parquet" else pcsv.read_csv(out)
    rows = table.to_pylist()
    temp = sorted((str(r["time"]), r["qc_agg"]) for r in rows if r["topic"] == TEMP)
    got = np.array([f for _, f in temp], dtype=np.uint8)
    np.testing.assert_array_equal(got, _expected(archive))
    _injected_are_flagged(got)
    assert all(r["qc_agg"] is None for r in rows if r["topic"] != TEMP)


def test_without_tests_or_range_no_flag_is_written(archive: Path, tmp_path: Path) -> None:
    out = tmp_path / "n.parquet"
    make_dataset([archive], _model(ranged=False), "parquet", out)
    assert "qc_agg" not in pq.read_schema(out).names


def test_the_models_range_alone_gives_a_gross_range_flag(archive: Path, tmp_path: Path) -> None:
    out = tmp_path / "r.csv"
    make_dataset([archive], _model(), "csv", out)
    rows = [r for r in pcsv.read_csv(out).to_pylist() if r["topic"] == TEMP]
    assert sorted({r["qc_agg"] for r in rows}) == [1, 4]  # only the value above validMax fails


@pytest.mark.parametrize(
    ("qc", "error"),
    [
        ({TEMP: {"spike": {}}}, "qc.boat.ctd.temp: unknown test 'spike'"),
        ({TEMP: {"spike_test": {"low": 1}}}, "qc.boat.ctd.temp.spike_test: unknown parameter"),
        ({TEMP: {"rate_of_change_test": {}}}, "rate_of_change_test: threshold is required"),
        ({TEMP: {"gross_range_test": {"fail_span": [3, 1]}}}, "fail_span: \\[low, high\\]"),
        ({TEMP: {"spike_test": {"fail_threshold": "x"}}}, "fail_threshold: a number"),
        ({TEMP: []}, "qc.boat.ctd.temp: a mapping of tests"),
        ([1], "qc: a mapping of topics"),
    ],
)
def test_bad_qc_config_is_a_located_error(qc: Any, error: str) -> None:
    with pytest.raises(MetadataError, match=error) as info:
        parse_metadata({"qc": qc}, "dataset.yaml")
    assert str(info.value).startswith("dataset.yaml")


def test_a_qc_topic_not_in_the_model_is_refused(archive: Path, tmp_path: Path) -> None:
    meta = parse_metadata({"qc": {"boat.ctd.tmp": {"spike_test": {}}}}, "dataset.yaml")
    with pytest.raises(DatasetError, match="dataset.yaml: qc.boat.ctd.tmp: not a topic"):
        make_dataset([archive], _model(), "csv", tmp_path / "x.csv", metadata=meta)
    # a topic of the model left out of the export is no error
    make_dataset(
        [archive], _model(), "csv", tmp_path / "y.csv", topics=["boat.gps.lat"], metadata=_meta()
    )


def test_faster_than_1_hz_the_timed_tests_run_in_scaled_time(tmp_path: Path) -> None:
    """At 10 Hz the timed tests run as ``ioos_qc`` would on the same samples a second
    apart with their parameters in that unit (a rate per second / 10, windows x 10):
    both tests are the same under a change of time unit."""
    path = write_archive(tmp_path / "fast.mcap", _mission(seconds=25, hz=10))
    tests = {
        "spike_test": QC[TEMP]["spike_test"],
        "rate_of_change_test": {"threshold": 5},
        "flat_line_test": {"suspect_threshold": 2, "fail_threshold": 4, "tolerance": 0.0001},
    }
    out = tmp_path / "f.parquet"
    summary = make_dataset(
        [path], _model(), "parquet", out, metadata=parse_metadata({"qc": {TEMP: tests}}, "d.yaml")
    )
    assert not any("not evaluated" in n for n in summary.notes), summary.notes
    rows = [r for r in pq.read_table(out).to_pylist() if r["topic"] == TEMP]
    got = np.array([r["qc_agg"] for r in sorted(rows, key=lambda r: r["time"])])
    with path.open("rb") as f:
        messages = make_reader(f).iter_messages(topics=[TEMP], log_time_order=True)
        v = np.ma.masked_invalid([json.loads(m.data)["value"] for _s, _c, m in messages])
    t = (T0 + np.arange(len(v)) * S).astype("datetime64[ns]")  # a second apart
    expected = qartod.qartod_compare(
        [
            qartod.gross_range_test(inp=v, fail_span=[0.0, 30.0]),
            qartod.spike_test(inp=v, **tests["spike_test"]),
            qartod.rate_of_change_test(inp=v, tinp=t, threshold=0.5),
            qartod.flat_line_test(
                inp=v, tinp=t, suspect_threshold=20, fail_threshold=40, tolerance=0.0001
            ),
        ]
    )
    assert np.array_equal(got, np.asarray(expected)), np.nonzero(got != expected)
    assert got[SPIKE] == 4 and got[-1] == 4
    assert got[STUCK[0] + 41 : STUCK[1]].min() == 4  # stuck 6 s, FAIL after 4 s


#: A box the track leaves (north) after its 200th fix: lat 47.0 + 1e-4 i.
BBOX = [-3.5, 46.5, -2.5, 47.01995]


def _positions(path: Path, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The oracle's position at ``times``: the fixes the official reader returns,
    interpolated by NumPy (NaN outside them)."""
    fixes: dict[str, list[tuple[int, float]]] = {"boat.gps.lat": [], "boat.gps.lon": []}
    with path.open("rb") as f:
        for _s, c, m in make_reader(f).iter_messages(topics=list(fixes), log_time_order=True):
            fixes[c.topic].append((m.log_time, json.loads(m.data)["value"]))
    out = []
    for topic in fixes:
        t, v = np.array(fixes[topic], dtype=np.float64).T
        out.append(np.interp(times.astype(np.float64), t, v, left=np.nan, right=np.nan))
    return out[0], out[1]


def _location_expected(lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    return np.asarray(
        qartod.qartod_compare(
            [
                qartod.location_test(lon=lon, lat=lat),
                qartod.location_bounds_test(lon=lon, lat=lat, shape=list(BBOX)),
            ]
        ),
        dtype=np.uint8,
    )


@pytest.mark.parametrize("fmt", ["netcdf", "parquet", "csv"])
def test_positions_get_the_location_test_of_ioos_qc(
    archive: Path, tmp_path: Path, fmt: str
) -> None:
    meta = parse_metadata({"qc": {"position": {"location_test": {"bbox": BBOX}}}}, "d.yaml")
    out = tmp_path / f"loc.{fmt}"
    make_dataset([archive], _model(), fmt, out, metadata=meta)
    if fmt == "netcdf":
        import xarray as xr

        with xr.open_dataset(out, mask_and_scale=False) as ds:
            assert ds["lat"].attrs["ancillary_variables"] == "location_qc_agg"
            assert ds["lon"].attrs["ancillary_variables"] == "location_qc_agg"
            assert ds["location_qc_agg"].attrs["flag_meanings"].startswith("PASS NOT_EVAL")
            time_ns = ds["time"].values[0].astype("datetime64[ns]").astype(np.int64)
            lat, lon = ds["lat"].values[0], ds["lon"].values[0]
            got = ds["location_qc_agg"].values[0].astype(np.uint8)
    else:
        table = pq.read_table(out) if fmt == "parquet" else pcsv.read_csv(out)
        import pyarrow as pa

        stamps = table["time"].cast(pa.timestamp("ns", tz="UTC"))
        time_ns = stamps.cast(pa.int64()).to_numpy()
        lat = table["lat"].to_numpy(zero_copy_only=False)
        lon = table["lon"].to_numpy(zero_copy_only=False)
        got = table["location_qc_agg"].to_numpy(zero_copy_only=False).astype(np.uint8)
    want_lat, want_lon = _positions(archive, time_ns)
    both = np.isfinite(lat) & np.isfinite(want_lat)
    np.testing.assert_allclose(lat[both], want_lat[both], rtol=0, atol=1e-9)
    np.testing.assert_allclose(lon[both], want_lon[both], rtol=0, atol=1e-9)
    # NetCDF keeps times as float seconds (~0.2 us): only at the track's ends may they differ
    ends = np.array([T0, T0 + 249 * S])
    odd = time_ns[np.isnan(lat) != np.isnan(want_lat)]
    assert (np.abs(odd[:, None] - ends).min(axis=1, initial=0) < 1000).all(), odd
    np.testing.assert_array_equal(got, _location_expected(lat, lon))
    assert sorted(set(got.tolist())) == [1, 4, 9]  # inside; north of the box; no position
    assert (got[lat > BBOX[3]] == 4).all() and (got[np.isnan(lat)] == 9).all()


def test_every_position_gets_the_location_test_by_default(archive: Path, tmp_path: Path) -> None:
    out = tmp_path / "d.parquet"
    make_dataset([archive], _model(ranged=False), "parquet", out)
    table = pq.read_table(out)
    got = table["location_qc_agg"].to_numpy().astype(np.uint8)
    lat, lon = table["lat"].to_numpy(), table["lon"].to_numpy()
    expected = np.asarray(qartod.location_test(lon=lon, lat=lat), dtype=np.uint8)
    np.testing.assert_array_equal(got, expected)
    assert sorted(set(got.tolist())) == [1, 9]


@pytest.mark.parametrize(
    ("qc", "error"),
    [
        ({"position": {"location_test": {"bbox": [1, 2, 3]}}}, "bbox: four numbers"),
        ({"position": {"location_test": {"bbox": [3, 0, 1, 2]}}}, "min < max"),
        ({"position": {"spike_test": {}}}, "qc.position: unknown test 'spike_test'"),
        ({TEMP: {"location_test": {}}}, "qc.boat.ctd.temp: unknown test 'location_test'"),
    ],
)
def test_bad_location_config_is_a_located_error(qc: Any, error: str) -> None:
    with pytest.raises(MetadataError, match=error):
        parse_metadata({"qc": qc}, "dataset.yaml")


def test_a_location_test_without_a_position_is_refused(archive: Path, tmp_path: Path) -> None:
    text = MODEL.replace("RANGE", "").replace(
        'Position { latitude = "boat.gps.lat"; longitude = "boat.gps.lon"; maxGap = 3; }', ""
    )
    result = load_text(text, "boat.modd")
    assert result.ok and result.model is not None
    model = result.model
    meta = parse_metadata({"qc": {"position": {"location_test": {}}}}, "dataset.yaml")
    with pytest.raises(DatasetError, match="qc.position: the model declares no position"):
        make_dataset([archive], model, "csv", tmp_path / "x.csv", metadata=meta)


def test_gts_ingest_marks_the_file_and_its_variables(archive: Path, tmp_path: Path) -> None:
    import netCDF4

    meta = parse_metadata({"qc": QC, "gts_ingest": [TEMP]}, "dataset.yaml")
    out = tmp_path / "g.nc"
    make_dataset([archive], _model(), "netcdf", out, metadata=meta)
    with netCDF4.Dataset(out) as ds:
        assert ds.gts_ingest == "true"
        assert [v.name for v in ds.get_variables_by_attributes(gts_ingest="true")] == ["ctd_temp"]
    plain = tmp_path / "p.nc"
    make_dataset([archive], _model(), "netcdf", plain, metadata=_meta())
    with netCDF4.Dataset(plain) as ds:
        assert "gts_ingest" not in ds.ncattrs()
    bad = parse_metadata({"gts_ingest": ["boat.ctd.tmp"]}, "dataset.yaml")
    with pytest.raises(DatasetError, match="dataset.yaml: gts_ingest: boat.ctd.tmp is not a topic"):
        make_dataset([archive], _model(), "netcdf", tmp_path / "b.nc", metadata=bad)
    with pytest.raises(MetadataError, match="dataset.yaml: gts_ingest: a list of topics"):
        parse_metadata({"gts_ingest": "yes"}, "dataset.yaml")
