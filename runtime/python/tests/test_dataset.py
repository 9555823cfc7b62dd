"""``modd dataset`` on archives written by the official ``mcap`` writer in the
archive record's form (contracts/vectors/archive_record.json), checked against
independent readings: the official ``mcap`` reader for the values, the
known track for the positions, xarray/pyarrow for the files. Bad input gets a
located error (file and offset) or a note, never a traceback."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from modd.dataset.build import DatasetError, make_dataset
from modd.dataset.cli import parse_period, parse_time
from modd.dataset.position import coordinate_at
from modd_model import load_text

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
T0 = 1_790_000_000 * 10**9  # 2026-09-21
S = 10**9
MODEL = """
Drone boat "Test boat" {
    Sensors {
        Sensor gps measures {
            lat(degree_north, float64); lon(degree_east, float64); alt("m");
        }
        Sensor ctd measures {
            temp(degC) { standardName = sea_water_temperature; longName = "Water temperature"; };
            count(NONE, int);
            wet(NONE, bool);
        }
    }
    Position {
        latitude = "boat.gps.lat"; longitude = "boat.gps.lon"; altitude = "boat.gps.alt";
        maxGap = 3;
    }
}
PubBroker("127.0.0.1":7171, "/tmp/l"); SubBroker("127.0.0.1":7272, "/tmp/c");
Publishers {
    Publisher gps(1, "boat.gps.lat", "boat.gps.lon", "boat.gps.alt");
    Publisher ctd(0.1, "boat.ctd.temp", "boat.ctd.count", "boat.ctd.wet");
}
Subscriptions { }
"""
TYPES = {
    "boat.gps.lat": "float64",
    "boat.gps.lon": "float64",
    "boat.gps.alt": "float32",
    "boat.ctd.temp": "float32",
    "boat.ctd.count": "int",
    "boat.ctd.wet": "bool",
}
Messages = list[tuple[str, int, Any]]


def _model() -> dict[str, Any]:
    result = load_text(MODEL, "boat.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def _data(value: Any) -> bytes:
    """The record as the PubBroker writes it (the contract's vectors say the form)."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, float) and not math.isfinite(value):
        text = "nan" if value != value else ("inf" if value > 0 else "-inf")
    else:
        text = repr(value)
    return b'{"value":' + text.encode() + b"}"


def write_archive(
    path: Path, messages: Messages, chunk_size: int = 4096, skew: dict[str, int] | None = None
) -> None:
    """An archive by the official writer, channels as the contract says; a
    topic's publish time is its log time plus its ``skew`` (ns)."""
    channels = {
        c["type"]: c for c in json.loads((VECTORS / "archive_record.json").read_text())["channels"]
    }
    with path.open("wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        w.start(profile="", library="test")
        ids: dict[str, int] = {}
        for topic, t, value in messages:
            if topic not in ids:
                c = channels[TYPES[topic]]
                sid = w.register_schema(
                    c["schema_name"], c["schema_encoding"], c["schema_data"].encode()
                )
                ids[topic] = w.register_channel(topic, c["message_encoding"], sid, c["metadata"])
            pub = t + (skew or {}).get(topic, 0)
            w.add_message(ids[topic], log_time=t, data=_data(value), publish_time=pub)
        w.finish()  # type: ignore[no-untyped-call]


def lat_at(t: float) -> float:
    return 47.0 + 1e-4 * t  # degrees; t in s since T0


def lon_at(t: float) -> float:
    return -3.0 - 2e-4 * t


def mission(seconds: int = 20) -> Messages:
    """Fixes at 1 Hz (on the known straight track), the CTD at 10 Hz."""
    out: Messages = []
    for i in range(seconds):
        t = T0 + i * S
        out += [
            ("boat.gps.lat", t, lat_at(i)),
            ("boat.gps.lon", t, lon_at(i)),
            ("boat.gps.alt", t, float(i % 3)),
        ]
        for k in range(10):
            tk = t + k * S // 10 + 12_345
            out += [
                ("boat.ctd.temp", tk, round(12 + 0.01 * (10 * i + k), 2)),
                ("boat.ctd.count", tk, 10 * i + k - 7),
                ("boat.ctd.wet", tk, k % 2 == 0),
            ]
    return out


def official(path: Path) -> dict[str, list[tuple[int, Any]]]:
    """The oracle: every sample as the official mcap reader and json read it."""
    out: dict[str, list[tuple[int, Any]]] = {}
    with path.open("rb") as f:
        for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
            out.setdefault(ch.topic, []).append((m.log_time, json.loads(m.data)["value"]))
    return out


@pytest.fixture
def archive(tmp_path: Path) -> Path:
    path = tmp_path / "boat-0.mcap"
    write_archive(path, mission())
    return path


def test_parquet_long_has_every_sample_with_the_archives_value(
    archive: Path, tmp_path: Path
) -> None:
    out = tmp_path / "d.parquet"
    summary = make_dataset([archive], _model(), "parquet", out)
    table = pq.read_table(out).to_pandas()
    truth = official(archive)
    assert summary.samples == len(table) == sum(len(v) for v in truth.values())
    for topic, samples in truth.items():
        rows = table[table["topic"] == topic]
        assert rows["time"].astype("int64").tolist() == [t for t, _ in samples]
        assert rows["value"].tolist() == [float(v) for _, v in samples], topic
    assert set(table[table["topic"] == "boat.ctd.temp"]["unit"]) == {"degC"}


def test_positions_are_the_track_interpolated(archive: Path, tmp_path: Path) -> None:
    out = tmp_path / "d.csv"
    make_dataset([archive], _model(), "csv", out)
    table = pcsv.read_csv(out).to_pandas()
    ctd = table[table["topic"] == "boat.ctd.temp"]
    secs = (ctd["time"].astype("int64") - T0) / 1e9
    inside = secs <= 19  # after the last fix: no position
    assert np.allclose(ctd["lat"][inside], [lat_at(s) for s in secs[inside]], atol=1e-9)
    assert np.allclose(ctd["lon"][inside], [lon_at(s) for s in secs[inside]], atol=1e-9)
    assert ctd["lat"][~inside].isna().all() and (~inside).sum() == 10  # the last second


def nc_series(ds: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    """A variable's samples in a MoDD NetCDF read with xarray (CF decoding): its
    observations are the rows where it is not the fill value. (times in ns, values)"""
    values = ds[name].values[0]
    keep = ~np.isnan(values)
    times = ds["time"].values[0].astype("datetime64[ns]").astype(np.int64)
    return times[keep], values[keep]


def test_netcdf_is_cf_and_holds_the_values(archive: Path, tmp_path: Path) -> None:
    import xarray as xr

    out = tmp_path / "d.nc"
    make_dataset([archive], _model(), "netcdf", out)
    truth = official(archive)
    with xr.open_dataset(out) as ds:
        assert ds.attrs["featureType"] == "trajectory"
        assert ds.attrs["Conventions"] == "CF-1.11, CF-1.6, ACDD-1.3, IOOS-1.2"
        assert ds["time"].dims == ds["ctd_temp"].dims == ("trajectory", "obs")
        assert ds.sizes["obs"] == sum(len(v) for v in truth.values())
        temp = ds["ctd_temp"]
        assert temp.attrs["units"] == "degC"
        assert temp.attrs["standard_name"] == "sea_water_temperature"
        assert temp.attrs["instrument"] == "instrument_ctd"
        times, values = nc_series(ds, "ctd_temp")
        want = np.array([v for _, v in truth["boat.ctd.temp"]], dtype=np.float32)
        assert np.array_equal(values, want)
        assert nc_series(ds, "ctd_count")[1].tolist() == [v for _, v in truth["boat.ctd.count"]]
        assert nc_series(ds, "ctd_wet")[1].tolist() == [int(v) for _, v in truth["boat.ctd.wet"]]
        assert np.abs(times - [t for t, _ in truth["boat.ctd.temp"]]).max() < 1000  # < 1 µs


def test_resampled_wide_form_is_the_mean_per_period(archive: Path, tmp_path: Path) -> None:
    out = tmp_path / "w.parquet"
    make_dataset([archive], _model(), "parquet", out, resample_s=2.0)
    table = pq.read_table(out).to_pandas()
    temps = official(archive)["boat.ctd.temp"]
    first = [v for t, v in temps if (t // (2 * S)) == (temps[0][0] // (2 * S))]
    assert table["ctd_temp"].iloc[0] == pytest.approx(sum(first) / len(first))
    assert list(table.columns[:4]) == ["time", "lat", "lon", "alt"]


def test_tracks_have_points_and_measurements(archive: Path, tmp_path: Path) -> None:
    gj, gpx = tmp_path / "t.geojson", tmp_path / "t.gpx"
    make_dataset([archive], _model(), "geojson", gj)
    make_dataset([archive], _model(), "gpx", gpx)
    features = json.loads(gj.read_text())["features"]
    assert features[0]["geometry"]["type"] == "LineString"
    points = features[1:]
    assert len(points) >= 18 and all("ctd_temp" in p["properties"] for p in points)
    lon, lat = points[3]["geometry"]["coordinates"][:2]
    t = np.datetime64(points[3]["properties"]["time"].rstrip("Z"), "ns").astype("int64") - T0
    assert lat == pytest.approx(lat_at(t / 1e9), abs=1e-9)
    import xml.etree.ElementTree as ET

    root = ET.parse(gpx).getroot()
    pts = root.findall(".//{http://www.topografix.com/GPX/1/1}trkpt")
    assert len(pts) == len(points) and float(pts[3].get("lat", "")) == pytest.approx(lat, abs=1e-8)


# -- bad input ----------------------------------------------------------------


def test_a_gap_in_the_fixes_gives_no_position() -> None:
    fix_t = np.array([0, 1, 10, 11], dtype=np.int64) * S
    got = coordinate_at(np.array([0.5, 5.0, 10.0, 10.5]) * S, fix_t, np.arange(4.0), 3 * S)
    assert got[0] == 0.5 and math.isnan(got[1]) and got[2] == 2.0 and got[3] == 2.5


def test_glitch_and_disorder_are_cleaned_and_said(tmp_path: Path) -> None:
    msgs = [m for m in mission(10) if not (m[0] == "boat.gps.lat" and m[1] == T0 + 5 * S)]
    msgs.append(("boat.gps.lat", T0 + 5 * S, 48.0))  # 111 km away: a GPS glitch, out of order
    msgs.append(("boat.gps.lon", T0 + 4 * S, float("nan")))  # a NaN fix (a repeated time too)
    path = tmp_path / "g.mcap"
    write_archive(path, msgs)
    out = tmp_path / "g.csv"
    summary = make_dataset([path], _model(), "csv", out)
    notes = "\n".join(summary.notes)
    assert "latitude: fixes out of time order; sorted" in notes
    assert "1 fixes jump faster than 100 m/s" in notes and "t=1790000005.000 s" in notes
    assert "longitude: 1 NaN/Inf fixes dropped" in notes
    table = pcsv.read_csv(out).to_pandas()
    lat = table[table["topic"] == "boat.ctd.temp"]["lat"]
    assert lat.max() < 47.01  # the glitch never reaches a sample
    # and in the NetCDF file's history (CF's audit trail), read by another reader
    import xarray as xr

    nc = tmp_path / "g.nc"
    nc_notes = make_dataset([path], _model(), "netcdf", nc).notes
    with xr.open_dataset(nc) as ds:
        history = ds.attrs["history"]
    assert all(f"note: {n}" in history for n in nc_notes) and "1 fixes jump faster" in history


def test_nan_samples_and_empty_topics_are_kept_and_said(tmp_path: Path) -> None:
    msgs = [m for m in mission(3) if m[0] != "boat.ctd.wet"]
    msgs.append(("boat.ctd.temp", T0 + 1, float("nan")))
    msgs.append(("boat.ctd.temp", T0 + 2, float("inf")))
    path = tmp_path / "n.mcap"
    write_archive(path, msgs)
    out = tmp_path / "n.parquet"
    summary = make_dataset([path], _model(), "parquet", out)
    assert "topic boat.ctd.temp: 2 NaN/Inf samples, kept as they were archived" in summary.notes
    assert "topic boat.ctd.wet: no sample in the range" in summary.notes
    values = pq.read_table(out).to_pandas().query("topic == 'boat.ctd.temp'")["value"]
    assert values.isna().sum() == 1 and np.isinf(values).sum() == 1


def test_a_cut_file_exports_up_to_its_last_complete_chunk(archive: Path, tmp_path: Path) -> None:
    data = archive.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    out = tmp_path / "c.parquet"
    summary = make_dataset([cut], _model(), "parquet", out)
    assert 0 < summary.samples < sum(len(v) for v in official(archive).values())
    assert any("not closed" in n and "modd archive recover" in n for n in summary.notes)
    table = pq.read_table(out).to_pandas()
    truth = official(archive)["boat.ctd.count"]
    got = table[table["topic"] == "boat.ctd.count"]["value"].tolist()
    assert got == [float(v) for _, v in truth[: len(got)]]  # a prefix, exactly


def test_a_cut_file_after_recover_exports_like_a_closed_one(archive: Path, tmp_path: Path) -> None:
    from modd.archive.recover import recover

    data = archive.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    fixed = tmp_path / "fixed.mcap"
    recover(cut, fixed)
    as_cut = make_dataset([cut], _model(), "parquet", tmp_path / "a.parquet")
    recovered = make_dataset([fixed], _model(), "parquet", tmp_path / "b.parquet")
    assert not any("not closed" in n for n in recovered.notes)
    assert recovered.samples == as_cut.samples
    a = pq.read_table(tmp_path / "a.parquet").to_pandas()
    b = pq.read_table(tmp_path / "b.parquet").to_pandas()
    assert a.equals(b)


def test_a_corrupt_chunk_is_a_located_error_and_leaves_no_file(
    archive: Path, tmp_path: Path
) -> None:
    data = bytearray(archive.read_bytes())
    at = data.index(b"zstd") + 4 + 8 + 20  # inside the first chunk's compressed records
    data[at] ^= 0xFF
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    out = tmp_path / "b.nc"
    with pytest.raises(DatasetError, match=r"bad\.mcap: offset \d+: chunk"):
        make_dataset([bad], _model(), "netcdf", out)
    assert not out.exists() and list(tmp_path.glob(".*part")) == []


def test_an_archive_of_another_model_is_said(tmp_path: Path) -> None:
    path = tmp_path / "o.mcap"
    TYPES["other.ctd.temp"] = "float32"
    write_archive(path, [*mission(2), ("other.ctd.temp", T0, 1.0)])
    summary = make_dataset([path], _model(), "csv", tmp_path / "o.csv")
    assert any("topic other.ctd.temp is not in the model" in n for n in summary.notes)
    mismatch = _model()
    mismatch["drone"]["sensors"][1]["variables"][1]["type"] = "float64"  # count: int archived
    with pytest.raises(DatasetError, match="boat.ctd.count is archived as int but the model says"):
        make_dataset([path], mismatch, "csv", tmp_path / "m.csv")


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"start_ns": T0 + 1000 * S}, "nothing to export"),
        ({"topics": ["ctd.salinity"]}, "unknown topic"),
        ({"start_ns": T0 + 5 * S, "end_ns": T0}, "--to must be after --from"),
    ],
)
def test_requests_with_nothing_to_answer_are_refused(
    archive: Path, tmp_path: Path, kwargs: dict[str, Any], message: str
) -> None:
    with pytest.raises(DatasetError, match=message):
        make_dataset([archive], _model(), "parquet", tmp_path / "x.parquet", **kwargs)


def test_a_track_without_position_is_refused(archive: Path, tmp_path: Path) -> None:
    model = _model()
    del model["drone"]["position"]
    with pytest.raises(DatasetError, match="gpx track needs the platform's position"):
        make_dataset([archive], model, "gpx", tmp_path / "x.gpx")


def test_not_an_archive_is_located(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not mcap at all")
    with pytest.raises(DatasetError, match=r"junk\.mcap: offset 0: not an MCAP file"):
        make_dataset([junk], _model(), "csv", tmp_path / "x.csv")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DatasetError, match="no .mcap file"):
        make_dataset([tmp_path / "empty"], _model(), "csv", tmp_path / "x.csv")


def test_time_and_period_arguments() -> None:
    assert parse_time("2026-09-21T00:00:00Z") == parse_time("2026-09-21T00:00:00")
    assert parse_time("1790000000.5") == 1_790_000_000_500_000_000
    assert parse_period("10s") == 10.0
    with pytest.raises(Exception, match="not a time"):
        parse_time("yesterday")
    with pytest.raises(Exception, match="period"):
        parse_period("0")


# -- every format x every option ------------------------------------------------

FORMATS = ("netcdf", "parquet", "csv", "geojson", "gpx")


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("period", [None, 0.05, 1.0, 2.5, 3600.0, 86_400.0])
def test_every_format_with_every_period_gives_a_valid_file(
    archive: Path, tmp_path: Path, fmt: str, period: float | None, dataset_valid: Any
) -> None:
    out = tmp_path / f"d.{fmt}"
    summary = make_dataset([archive], _model(), fmt, out, resample_s=period)
    rows = dataset_valid(fmt, out)
    truth = official(archive)
    times = {t for samples in truth.values() for t, _ in samples}
    if fmt in ("geojson", "gpx"):  # one point per period whose centre has a position
        # an hour's centre is far outside the 20 s track: no point, and the notes say so
        assert rows >= 1 if (period or 1) < 20 else rows == 0
        assert rows > 0 or any("have no position and were left out" in n for n in summary.notes)
    elif period is None:
        assert rows == summary.samples == sum(len(v) for v in truth.values())
    else:  # one row per period with a sample
        step = int(round(period * S))
        assert rows == len({t // step for t in times})


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("fixes", [0, 1, 2])
def test_an_export_of_few_positions_is_a_valid_file(
    tmp_path: Path, fmt: str, fixes: int, dataset_valid: Any
) -> None:
    msgs = [m for m in mission(3) if not m[0].startswith("boat.gps")]
    msgs += [("boat.gps.lat", T0 + i * S, lat_at(i)) for i in range(fixes)]
    msgs += [("boat.gps.lon", T0 + i * S, lon_at(i)) for i in range(fixes)]
    path = tmp_path / "few.mcap"
    write_archive(path, msgs)
    out = tmp_path / f"few.{fmt}"
    make_dataset([path], _model(), fmt, out)
    rows = dataset_valid(fmt, out)
    if fmt in ("geojson", "gpx"):  # 1 s points: one at each fix (the fix's period centre
        assert rows <= fixes  # is inside the track only between two fixes)


def test_metadata_reaches_every_format(archive: Path, tmp_path: Path) -> None:
    import xarray as xr
    from modd.dataset.metadata import parse_metadata

    meta = parse_metadata(
        {
            "creator_name": "Ana Example",
            "license": "CC-BY-4.0",
            "naming_authority": "org.example.marine",
            "platform": {"name": "Test boat", "id": "boat01", "vocabulary": "https://x.org/p"},
            "instruments": {"ctd": {"make": "Sea-Bird", "model": "SBE 37", "serial_number": 7}},
        },
        "dataset.yaml",
    )
    nc, pa_out = tmp_path / "m.nc", tmp_path / "m.parquet"
    summary = make_dataset([archive], _model(), "netcdf", nc, metadata=meta)
    make_dataset([archive], _model(), "parquet", pa_out, metadata=meta)
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["creator_name"] == "Ana Example"
        assert ds.attrs["naming_authority"] == "org.example.marine"
        assert ds["trajectory"].values[0] == b"boat01"
        assert ds["instrument_ctd"].attrs["make_model"] == "Sea-Bird SBE 37"
        assert ds["instrument_ctd"].attrs["serial_number"] == "7"
        assert ds["platform"].attrs["platform_vocabulary"] == "https://x.org/p"
    assert any("ask for creator_email" in n and "dataset.yaml" in n for n in summary.notes)
    modd = json.loads(pq.read_schema(pa_out).metadata[b"modd"])
    assert modd["metadata"]["license"] == "CC-BY-4.0"
    assert modd["topics"]["boat.ctd.temp"]["standard_name"] == "sea_water_temperature"


@pytest.mark.parametrize(
    ("doc", "error"),
    [
        ({"creator": "x"}, "unknown key 'creator'"),
        ({"naming_authority": "modd"}, "not reversed DNS"),
        ({"platform": {"colour": "red"}}, "platform: unknown key 'colour'"),
        ({"instruments": {"ctd": {"make": {"a": 1}}}}, "instruments.ctd.make: a text"),
        (["a"], "a mapping"),
    ],
)
def test_bad_metadata_is_a_located_error(doc: Any, error: str) -> None:
    from modd.dataset.metadata import MetadataError, parse_metadata

    with pytest.raises(MetadataError, match=error) as info:
        parse_metadata(doc, "dataset.yaml")
    assert str(info.value).startswith("dataset.yaml")


def test_notes_name_files_not_server_paths(archive: Path, tmp_path: Path) -> None:
    data = archive.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    summary = make_dataset([cut], _model(), "csv", tmp_path / "c.csv")
    assert summary.notes and not any(str(tmp_path) in n for n in summary.notes)
    assert any(n.startswith("cut.mcap: not closed") for n in summary.notes)


# -- both clocks ------------------------------------------------------------------

#: The GNSS's own clock, 395 million seconds ahead of the companion computer's.
SKEW = 395_000_000 * S


def _two_clock_model() -> dict[str, Any]:
    text = MODEL.replace(
        "Sensor gps measures {",
        'Sensor gps kind nmea on "/dev/ttyACM0" { clock = instrument; } measures {',
    )
    for v, f in (
        ("lat(degree_north, float64)", "GGA.lat"),
        ("lon(degree_east, float64)", "GGA.lon"),
    ):
        text = text.replace(f"{v};", f"{v} from sentence {f};")
    text = text.replace('alt("m");', 'alt("m") from sentence GGA.altitude;')
    result = load_text(text, "boat.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


@pytest.mark.parametrize("fmt", ["netcdf", "parquet", "csv"])
@pytest.mark.parametrize("clock", ["receive", "instrument"])
def test_both_clocks_are_written_and_either_is_the_axis(
    tmp_path: Path, fmt: str, clock: str
) -> None:
    path = tmp_path / "two.mcap"
    gps = {t: SKEW for t in ("boat.gps.lat", "boat.gps.lon", "boat.gps.alt")}
    write_archive(path, mission(5), skew=gps)
    out = tmp_path / f"two.{fmt}"
    make_dataset([path], _two_clock_model(), fmt, out, clock=clock)
    other = "receive_time" if clock == "instrument" else "instrument_time"
    truth: dict[str, list[tuple[int, int]]] = {}
    with path.open("rb") as f:  # the oracle: both times as the official reader reads them
        for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
            truth.setdefault(ch.topic, []).append((m.log_time, m.publish_time))
    for topic in ("boat.gps.lat", "boat.ctd.temp"):
        instrument = topic.startswith("boat.gps")
        log, pub = (np.array(x, dtype=np.int64) for x in zip(*truth[topic], strict=True))
        axis = pub if clock == "instrument" and instrument else log
        second = log if clock == "instrument" else (pub if instrument else None)
        got_axis, got_other = _times_of(fmt, out, topic, other)
        assert np.abs(got_axis - axis).max() < 1000, (topic, "axis")
        if second is None:
            assert np.isnan(got_other).all(), topic
        else:
            assert np.abs(got_other - second).max() < 1000, (topic, other)


def _times_of(fmt: str, out: Path, topic: str, other: str) -> tuple[np.ndarray, np.ndarray]:
    """(axis, other clock) of a topic's samples, in ns (float; NaN for none)."""
    if fmt == "netcdf":
        import netCDF4

        with netCDF4.Dataset(out) as ds:
            name = topic.split(".", 1)[1].replace(".", "_")
            rows = ~np.ma.getmaskarray(ds[name][0, :])
            axis = ds["time"][0, :][rows].astype(np.float64) * 1e9
            return axis, np.ma.filled(ds[other][0, :][rows], np.nan) * 1e9
    table = pq.read_table(out) if fmt == "parquet" else pcsv.read_csv(out)
    frame = table.to_pandas()
    rows = frame[frame["topic"] == topic]
    axis = rows["time"].astype("int64").to_numpy(dtype=np.float64)
    second = rows[other]
    if second.isna().all():
        return axis, np.full(len(rows), np.nan)
    return axis, second.astype("int64").to_numpy(dtype=np.float64)


def test_instrument_axis_without_an_instrument_clock_is_refused(
    archive: Path, tmp_path: Path
) -> None:
    with pytest.raises(DatasetError, match="no sensor of the chosen topics declares clock"):
        make_dataset([archive], _model(), "csv", tmp_path / "x.csv", clock="instrument")


def test_the_projects_dataset_yaml_beside_the_model_is_read(
    archive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import argparse

    import netCDF4
    from modd.dataset.cli import register

    (tmp_path / "boat.modd").write_text(MODEL)
    (tmp_path / "dataset.yaml").write_text("creator_name: Ana Example\nlicense: CC-BY-4.0\n")
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    out = tmp_path / "p.nc"
    argv = ["dataset", str(archive), "--model", str(tmp_path / "boat.modd")]
    args = parser.parse_args([*argv, "--format", "netcdf", "-o", str(out)])
    assert args.func(args) == 0
    with netCDF4.Dataset(out) as ds:
        assert ds.creator_name == "Ana Example" and ds.license == "CC-BY-4.0"
    (tmp_path / "dataset.yaml").write_text("license: [CC-BY-4.0, {a: 1}]\n")
    assert args.func(args) == 1
    assert "dataset.yaml: license: a text or a list of texts" in capsys.readouterr().err
