"""``modd dataset --received``: the windows the subscribers received, from a
base-station record written by the SubBroker's own recorder
(``modd.subbroker.record.BaseRecord``), checked against the record read
independently (the official ``mcap`` reader, the delivered-value contract's
``samples`` for how an ALL window spreads), in NetCDF, Parquet and CSV."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader
from modd.dataset.build import DatasetError, make_dataset
from modd.subbroker.payload import DeliveredValue
from modd.subbroker.record import BaseRecord
from modd_model import load_text

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
T0 = 1_790_000_000 * 10**9
S = 10**9
MODEL = """
Drone boat "Test boat" {
    Sensors {
        Sensor gps measures { lat(degree_north, float64); lon(degree_east, float64); }
        Sensor ctd measures {
            temp(degC) { standardName = sea_water_temperature; };
            wet(NONE, bool);
        }
    }
    Position { latitude = "boat.gps.lat"; longitude = "boat.gps.lon"; maxGap = 3; }
}
PubBroker("127.0.0.1":7171, "/tmp/l"); SubBroker("127.0.0.1":7272, "/tmp/c");
Publishers {
    Publisher gps(1, "boat.gps.lat", "boat.gps.lon");
    Publisher ctd(0.1, "boat.ctd.temp", "boat.ctd.wet");
}
Subscriptions {
    Subscriber fix_lat("127.0.0.1":7401, "boat.gps.lat", 1.0, LAST);
    Subscriber fix_lon("127.0.0.1":7402, "boat.gps.lon", 1.0, LAST);
    Subscriber temp_avg("127.0.0.1":7403, "boat.ctd.temp", 1.0, AVERAGE);
    Subscriber temp_min("127.0.0.1":7404, "boat.ctd.temp", 0.5, MIN);
    Subscriber temp_all("127.0.0.1":7405, "boat.ctd.temp", 1.0, ALL);
    Subscriber temp_n("127.0.0.1":7406, "boat.ctd.temp", 1.0, COUNT);
    Subscriber wet("127.0.0.1":7407, "boat.ctd.wet", 1.0, LAST);
}
"""


def _model() -> dict[str, Any]:
    result = load_text(MODEL, "boat.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def _window(sub: dict[str, Any], k: int) -> DeliveredValue:
    period = int(float(sub["periodS"]) * S)
    start = T0 + k * period
    agg, name = sub["aggregation"], sub["name"]
    value: Any
    count: int | None = None
    if name == "fix_lat":
        value = 45.0 + 1e-4 * k
    elif name == "fix_lon":
        value = -3.0 + 2e-4 * k
    elif agg == "ALL":
        value = [12.0 + 0.1 * i + k for i in range(k % 4)]  # k % 4 == 0: an empty window
        count = len(value)
    elif agg == "COUNT":
        value = count = 10
    elif name == "wet":
        value = k % 2 == 0
    else:
        value = 12.5 + 0.01 * k
        count = 10 if agg == "AVERAGE" else None
    if k == 3 and agg == "MIN":
        value = None  # an empty window
    return DeliveredValue(
        name,
        sub["topic"],
        agg,
        sub["periodS"],
        "CELSIUS",
        1,
        k,
        start,
        start + period,
        value,
        count,
        start + period + 5_000_000,
        backfilled=k == 7,
    )


def _record(root: Path, seconds: int) -> Path:
    """``seconds`` of every subscriber, recorded by the SubBroker's recorder."""
    rec = BaseRecord(root, "boat")
    rec.begin("survey", T0)
    for sub in _model()["subscribers"]:
        for k in range(int(seconds / float(sub["periodS"]))):
            rec.put(sub["name"], _window(sub, k).to_json())
    rec.close()
    return root / "boat"


@pytest.fixture
def record(tmp_path: Path) -> Path:
    return _record(tmp_path / "records", 20)


def _independent(folder: Path) -> dict[str, list[tuple[int, float]]]:
    """(time, value) per subscriber from the record read by the official reader:
    a window at its end, an ALL window's samples where the contract puts them."""
    out: dict[str, list[tuple[int, float]]] = {}
    for path in sorted(folder.glob("*.mcap")):
        with path.open("rb") as f:
            for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
                d = json.loads(m.data)
                rows = out.setdefault(ch.topic.rsplit("/", 1)[1], [])
                v = d["value"]
                if isinstance(v, list) and v:
                    rows += [
                        (
                            d["start_ns"] + (i + 1) * (d["end_ns"] - d["start_ns"]) // len(v),
                            float(x),
                        )
                        for i, x in enumerate(v)
                    ]
                else:
                    rows.append((d["end_ns"], float("nan") if v in (None, []) else float(v)))
    return out


def _marks(folder: Path) -> dict[str, list[tuple[int, int]]]:
    """(time, 1 if backfilled else 0) per subscriber and point, from the record read
    by the official reader: every point of a window carries the window's mark."""
    out: dict[str, list[tuple[int, int]]] = {}
    for path in sorted(folder.glob("*.mcap")):
        with path.open("rb") as f:
            for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
                d = json.loads(m.data)
                mark = 1 if d.get("backfilled") is True else 0
                n = len(d["value"]) if isinstance(d["value"], list) and d["value"] else 1
                times = (
                    [d["end_ns"]]
                    if n == 1 and not isinstance(d["value"], list)
                    else [
                        d["start_ns"] + (i + 1) * (d["end_ns"] - d["start_ns"]) // n
                        for i in range(n)
                    ]
                )
                out.setdefault(ch.topic.rsplit("/", 1)[1], []).extend((t, mark) for t in times)
    return out


def _same(got: list[tuple[int, float]], want: list[tuple[int, float]]) -> bool:
    return len(got) == len(want) and all(
        t1 == t2 and (v1 == v2 or (np.isnan(v1) and np.isnan(v2)))
        for (t1, v1), (t2, v2) in zip(sorted(got), sorted(want), strict=True)
    )


def test_the_contract_spreads_all_windows_as_the_export_does() -> None:
    """The delivered-value vectors' ``samples`` (what a chart plots) are the
    times and values the export gives an ALL window."""
    from modd.dataset.received import window_points

    for vector in json.loads((VECTORS / "delivered_value.json").read_text())["vectors"]:
        d = json.loads(vector["line"])
        times, values = window_points(d["start_ns"], d["end_ns"], d["value"])
        pts = [
            (t / 1e9, v)
            for t, v in zip(times.tolist(), values.tolist(), strict=True)
            if not np.isnan(v)
        ]
        assert pts == [(pytest.approx(t, abs=1e-6), v) for t, v in vector["samples"]], vector


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_tables_hold_every_received_window(record: Path, tmp_path: Path, fmt: str) -> None:
    out = tmp_path / f"received.{fmt}"
    summary = make_dataset([record], _model(), fmt, out, received=True)
    arrow = pq.read_table(out) if fmt == "parquet" else pcsv.read_csv(out)
    ns_col = arrow["time"].cast(pa.timestamp("ns", tz="UTC")).cast(pa.int64()).to_pylist()
    table = arrow.to_pydict() | {"time": ns_col}
    want = _independent(record)
    assert set(table["topic"]) == set(want) == set(summary.per_topic)
    got: dict[str, list[tuple[int, float]]] = {}
    for ns, topic, v in zip(table["time"], table["topic"], table["value"], strict=True):
        got.setdefault(topic, []).append((ns, float("nan") if v is None else v))
    for name, rows in want.items():
        assert _same(got[name], rows), name
    # every backfilled window is marked historical, the live ones not (the record's mark)
    marks: dict[str, list[tuple[int, int]]] = {}
    for ns, topic, b in zip(table["time"], table["topic"], table["backfilled"], strict=True):
        marks.setdefault(topic, []).append((ns, b))
    want_marks = _marks(record)
    assert {n: sorted(m) for n, m in marks.items()} == {n: sorted(m) for n, m in want_marks.items()}
    assert 0 < sum(b for m in marks.values() for _t, b in m) < sum(map(len, marks.values()))
    units = dict(zip(table["topic"], table["unit"], strict=True))
    assert units["temp_avg"] == "degC" and units["temp_n"] == "1"
    # the position: the received fixes, interpolated to each window's time
    fix_t, fix_v = np.array(sorted(want["fix_lat"])).T
    for ns, la in zip(table["time"], table["lat"], strict=True):
        if fix_t[0] <= ns <= fix_t[-1]:
            assert la == pytest.approx(float(np.interp(ns, fix_t, fix_v)), abs=1e-9)
        else:
            assert la is None or np.isnan(la)  # outside the received track: no position


def nc_series(ds: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    """A subscriber's windows with a value, read with xarray: (times in ns, values)."""
    values = ds[name].values[0]
    keep = ~np.isnan(values)
    return ds["time"].values[0].astype("datetime64[ns]").astype(np.int64)[keep], values[keep]


def test_netcdf_holds_every_received_window_with_its_cell_method(
    record: Path, tmp_path: Path
) -> None:
    import xarray as xr

    out = tmp_path / "received.nc"
    make_dataset([record], _model(), "netcdf", out, received=True)
    want = _independent(record)
    with xr.open_dataset(out) as ds:
        assert "windows received" in ds.attrs["title"]
        assert ds.attrs["source"] == "MoDD base-station record (MCAP)"
        empty = 0
        for name, rows in want.items():
            # the windows with a value; an empty one is a row of fill values
            got = list(zip(*(a.tolist() for a in nc_series(ds, name)), strict=True))
            full = [(t, v) for t, v in rows if not np.isnan(v)]
            empty += len(rows) - len(full)
            # NetCDF times are float64 seconds: equal to the microsecond
            assert len(got) == len(full), name
            for (t1, v1), (t2, v2) in zip(sorted(got), sorted(full), strict=True):
                assert abs(t1 - t2) < 1000 and v1 == v2, (name, t1, t2, v1, v2)
        values = np.stack([ds[name].values[0] for name in want])
        assert int(np.isnan(values).all(axis=0).sum()) == empty
        assert ds.sizes["obs"] == sum(len(rows) for rows in want.values())
        assert ds["temp_avg"].attrs["cell_methods"] == "time: mean (interval: 1 s)"
        assert ds["temp_min"].attrs["cell_methods"] == "time: minimum (interval: 0.5 s)"
        assert ds["temp_all"].attrs["cell_methods"] == "time: point"
        assert ds["temp_avg"].attrs["standard_name"] == "sea_water_temperature"
        assert "cell_methods" not in ds["temp_n"].attrs and ds["temp_n"].attrs["units"] == "1"
        # the historical mark: a CF flag variable, ancillary to every subscriber's
        flag = ds["backfilled"]
        assert list(flag.attrs["flag_values"]) == [0, 1]
        assert flag.attrs["flag_meanings"] == "live backfilled"
        assert "backfilled" in ds["temp_avg"].attrs["ancillary_variables"].split()
        times = ds["time"].values[0].astype("datetime64[ns]").astype(np.int64)
        got_marks = {}
        for name in want:
            has = ~np.isnan(ds[name].values[0])
            got_marks[name] = sorted(
                zip(times[has].tolist(), flag.values[0][has].astype(int).tolist(), strict=True)
            )
        for name, mark_rows in _marks(record).items():
            marked = sorted(
                (t, b)
                for (t, b), (_t, v) in zip(sorted(mark_rows), sorted(want[name]), strict=True)
                if not np.isnan(v)
            )
            assert [b for _t, b in got_marks[name]] == [b for _t, b in marked], name
            assert any(b for _t, b in marked), name


def test_subscribers_chosen_and_a_cut_record(record: Path, tmp_path: Path) -> None:
    out = tmp_path / "some.csv"
    summary = make_dataset(
        [record], _model(), "csv", out, received=True, topics=["temp_min", "boat.gps.lat"]
    )
    assert set(summary.per_topic) == {"temp_min", "fix_lat"}
    assert any("subscriber wet left out" in n for n in summary.notes), summary.notes
    with pytest.raises(DatasetError, match="no subscriber of nope"):
        make_dataset([record], _model(), "csv", out, received=True, topics=["nope"])
    # a record cut by a crash: exported up to its last complete chunk, with a note
    long = _record(tmp_path / "long", 3000)
    src = next(long.glob("*.mcap"))
    cut = tmp_path / "cut" / src.name
    cut.parent.mkdir()
    shutil.copy(src, cut)
    with open(cut, "r+b") as f:
        f.truncate(src.stat().st_size * 2 // 3)
    summary = make_dataset(
        [cut.parent], _model(), "parquet", tmp_path / "cut.parquet", received=True
    )
    assert 0 < summary.samples < sum(len(v) for v in _independent(long).values())
    assert any("not closed" in n for n in summary.notes)
    # an archive is not a record: nothing of it is a subscriber's window
    with pytest.raises(DatasetError, match="no window of the chosen subscribers"):
        make_dataset([record], _model(), "csv", out, received=True, start_ns=T0 + 1000 * S)


def test_a_record_being_written_exports_up_to_its_last_chunk(tmp_path: Path) -> None:
    """The SubBroker's record, still open: its windows reach the disk in small
    chunks, so an export made during the mission has all but the last seconds."""
    rec = BaseRecord(tmp_path / "records", "boat")
    rec.begin("survey", T0)
    sub = next(s for s in _model()["subscribers"] if s["name"] == "temp_avg")
    try:
        for k in range(2000):  # ~0.5 MB of windows: half a chunk of the mcap writer's default
            rec.put(sub["name"], _window(sub, k).to_json())
        summary = make_dataset(
            [tmp_path / "records" / "boat"],
            _model(),
            "csv",
            tmp_path / "live.csv",
            received=True,
            topics=["temp_avg"],
        )
    finally:
        rec.close()
    assert 1500 < summary.samples < 2000, summary.samples
    assert any("not closed" in n for n in summary.notes)


@pytest.mark.parametrize("fmt", ["netcdf", "parquet", "csv", "geojson", "gpx"])
@pytest.mark.parametrize("period", [None, 0.25, 1.0, 7.0, 86_400.0])
def test_received_in_every_format_and_period(
    record: Path, tmp_path: Path, fmt: str, period: float | None, dataset_valid: Any
) -> None:
    out = tmp_path / f"r.{fmt}"
    summary = make_dataset([record], _model(), fmt, out, received=True, resample_s=period)
    rows = dataset_valid(fmt, out)
    want = _independent(record)
    if fmt in ("geojson", "gpx"):
        assert rows > 0 or (period or 1) > 20
    elif period is None:
        assert rows == summary.samples == sum(len(w) for w in want.values())
    else:
        step = int(round(period * S))
        assert rows == len({t // step for w in want.values() for t, _ in w})


def test_the_exact_statistics_have_their_cf_cell_methods() -> None:
    """CF Appendix E's method names (median, standard_deviation, range)."""
    from modd.dataset.received import cell_methods

    assert cell_methods("MEDIAN", "1.0") == "time: median (interval: 1 s)"
    assert cell_methods("STDDEV", "0.5") == "time: standard_deviation (interval: 0.5 s)"
    assert cell_methods("RANGE", "0.25") == "time: range (interval: 0.25 s)"
    # CF has no percentile method (Appendix E): none, the long_name says which
    assert cell_methods("PERCENTILE(95)", "1.0") is None


def test_a_percentile_subscriber_is_named_by_its_label() -> None:
    from modd.dataset.plan import Variable
    from modd.dataset.received import _subscriber_variable

    topic = Variable("usv.ctd.turb", "turb", "1", "float32", None, "turbidity", None, None)
    sub = {"name": "p95", "topic": "usv.ctd.turb", "periodS": "10.0", "aggregation": "PERCENTILE"}
    var = _subscriber_variable({**sub, "percentile": 95.0}, topic)
    assert var.cell_methods is None
    assert var.long_name == (
        "PERCENTILE(95) of usv.ctd.turb over 10 s windows (numpy.percentile, linear) "
        "(subscriber p95)"
    )


@pytest.mark.parametrize("fmt", ["parquet", "csv", "netcdf"])
@pytest.mark.parametrize("period", [1.0, 7.0])
def test_a_resampled_period_says_whether_a_backfilled_window_is_in_it(
    record: Path, tmp_path: Path, fmt: str, period: float
) -> None:
    """``--received --resample``: each period's ``backfilled`` is 1 exactly when a
    window the record marks backfilled went into its mean (the record read by the
    official reader), so a historical value is never taken for a live one."""
    out = tmp_path / f"r.{fmt}"
    make_dataset([record], _model(), fmt, out, received=True, resample_s=period)
    step = int(round(period * S))
    marks = [(t // step, b) for m in _marks(record).values() for t, b in m]
    want = {k: int(any(b for kk, b in marks if kk == k)) for k, _ in marks}
    if fmt == "netcdf":
        import xarray as xr

        with xr.open_dataset(out) as ds:
            times = ds["time"].values[0].astype("datetime64[ns]").astype(np.int64)
            flags = ds["backfilled"].values[0].astype(int).tolist()
            assert "went into the period's mean" in ds["backfilled"].attrs["long_name"]
            assert "backfilled" in ds["temp_avg"].attrs["ancillary_variables"].split()
    else:
        arrow = pq.read_table(out) if fmt == "parquet" else pcsv.read_csv(out)
        times = arrow["time"].cast(pa.timestamp("ns", tz="UTC")).cast(pa.int64()).to_numpy()
        flags = arrow["backfilled"].to_pylist()
    got = {int(t) // step: int(f) for t, f in zip(times.tolist(), flags, strict=True)}
    assert got == want
    assert 0 < sum(got.values()) < len(got)
