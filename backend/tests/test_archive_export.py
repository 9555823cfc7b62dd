"""Archives → Export dataset: the route streams the file ``modd dataset``
makes (in a worker process), refuses a range with nothing in it or too much
in it, an invalid model and a corrupt file with a clear 4xx, and the service
keeps answering."""

from __future__ import annotations

import datetime as dt
import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, archive_work, create_app
from modd_model import load_text

from .conftest import ADMIN_PASSWORD, Headers, login
from .test_archives import STEP, T0, TOPICS, write_archive

MODEL = """
Drone usv { Sensors { Sensor accelerometer measures { accel_x(METER_PER_SECOND_SQUARED);
    accel_z(METER_PER_SECOND_SQUARED); } } }
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers { Publisher p(0.04, "usv.accelerometer.accel_x", "usv.accelerometer.accel_z"); }
Subscriptions { }
"""


def _model() -> dict[str, Any]:
    result = load_text(MODEL)
    assert result.ok and result.model is not None
    return result.model


def archive_settings(tmp_path: Path, samples: int, name: str) -> tuple[Settings, Path]:
    """A backend's settings with one archive of drone usv, ``samples`` long; its archive dir."""
    root = tmp_path / "archives"
    (root / "usv").mkdir(parents=True)
    write_archive(root / "usv" / name, samples)
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=root,
    )
    return settings, root


@pytest.fixture
def client(tmp_path: Path) -> Iterator[tuple[TestClient, Headers, Path]]:
    settings, root = archive_settings(tmp_path, 500, "run-0000.mcap")
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        yield c, login(c, "admin", ADMIN_PASSWORD), root


URL = "/api/drones/usv/archives/export"


def test_export_parquet_is_every_sample(
    client: tuple[TestClient, Headers, Path], tmp_path: Path
) -> None:
    c, h, _ = client
    r = c.post(URL, json={"model": _model(), "format": "parquet"}, headers=h)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "application/vnd.apache.parquet"
    span = "-".join(
        dt.datetime.fromtimestamp(t // 10**9, dt.UTC).strftime("%Y%m%dT%H%M%SZ")
        for t in (T0, T0 + 499 * STEP)
    )
    assert f'filename="usv-dataset-{span}.parquet"' in r.headers["content-disposition"]
    assert "no position" in r.headers["x-modd-notes"]
    (tmp_path / "d.parquet").write_bytes(r.content)
    table = pq.read_table(tmp_path / "d.parquet").to_pandas()
    x = table[table["topic"] == TOPICS[0]]
    assert x["value"].tolist() == [float(i % 50) for i in range(500)]  # as write_archive wrote
    assert x["time"].astype("int64").tolist() == [T0 + i * STEP for i in range(500)]
    assert set(x["unit"]) == {"m s-2"}


def test_export_netcdf_of_a_range(client: tuple[TestClient, Headers, Path], tmp_path: Path) -> None:
    import xarray as xr

    c, h, _ = client
    body = {
        "model": _model(),
        "format": "netcdf",
        "start_ns": T0 + 100 * STEP,
        "end_ns": T0 + 200 * STEP,
        "topics": ["accel_z"],
    }
    r = c.post(URL, json=body, headers=h)
    assert r.status_code == 200, r.text
    (tmp_path / "d.nc").write_bytes(r.content)
    with xr.open_dataset(tmp_path / "d.nc") as ds:
        assert ds["accelerometer_accel_z"].values[0].tolist() == [
            -float(i) for i in range(100, 200)
        ]
        assert "accelerometer_accel_x" not in ds


def test_export_carries_the_dataset_metadata(
    client: tuple[TestClient, Headers, Path], tmp_path: Path
) -> None:
    import xarray as xr

    c, h, _ = client
    meta = {"creator_name": "Ana Example", "platform": {"id": "usv01"}}
    body = {"model": _model(), "format": "netcdf", "metadata": meta}
    r = c.post(URL, json=body, headers=h)
    assert r.status_code == 200, r.text
    (tmp_path / "m.nc").write_bytes(r.content)
    with xr.open_dataset(tmp_path / "m.nc") as ds:
        assert ds.attrs["creator_name"] == "Ana Example"
        assert ds["trajectory"].values[0] == b"usv01"
    bad = c.post(URL, json=body | {"metadata": {"naming_authority": "modd"}}, headers=h)
    assert bad.status_code == 422 and "not reversed DNS" in bad.text, bad.text


def test_bad_requests_get_a_clear_4xx(
    client: tuple[TestClient, Headers, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    c, h, root = client
    empty = c.post(URL, json={"model": _model(), "format": "csv", "start_ns": T0 * 2}, headers=h)
    assert empty.status_code == 422 and "nothing to export" in empty.json()["detail"]
    bad = _model()
    bad["drone"]["sensors"][0]["variables"][0]["unit"] = "bananas"
    invalid = c.post(URL, json={"model": bad, "format": "csv"}, headers=h)
    assert invalid.status_code == 422
    assert "not a UDUNITS-2 unit" in invalid.json()["detail"]["errors"][0]
    monkeypatch.setattr(archive_work, "MAX_EXPORT_SAMPLES", 100)
    huge = c.post(URL, json={"model": _model(), "format": "netcdf"}, headers=h)
    assert huge.status_code == 413 and "more than 100 samples" in huge.json()["detail"]
    data = bytearray((root / "usv" / "run-0000.mcap").read_bytes())
    data[data.index(b"zstd") + 40] ^= 0xFF
    (root / "usv" / "run-0000.mcap").write_bytes(bytes(data))
    corrupt = c.post(URL, json={"model": _model(), "format": "csv"}, headers=h)
    assert corrupt.status_code == 422
    assert "<archives>/usv/run-0000.mcap: offset" in corrupt.json()["detail"]
    assert c.get("/api/health").status_code == 200  # the service keeps answering
    assert c.post(URL, json={"model": _model(), "format": "csv"}).status_code == 401


def test_export_the_windows_the_subscribers_received(tmp_path: Path) -> None:
    """``source: received``: the base-station record's windows (written by the
    SubBroker's recorder), equal to the record read by the official reader."""
    import json

    from mcap.reader import make_reader
    from modd.subbroker.payload import DeliveredValue
    from modd.subbroker.record import BaseRecord

    text = MODEL.replace(
        "Subscriptions { }",
        'Subscriptions { Subscriber avg("127.0.0.1":7401, "usv.accelerometer.accel_x", 0.5,'
        " AVERAGE); }",
    )
    result = load_text(text)
    assert result.ok and result.model is not None
    rec = BaseRecord(tmp_path / "records", "usv")
    rec.begin("m", T0)
    for k in range(40):
        start = T0 + k * 500_000_000
        value = None if k == 5 else 0.25 * k
        rec.put(
            "avg",
            DeliveredValue(
                "avg",
                "usv.accelerometer.accel_x",
                "AVERAGE",
                "0.5",
                "M",
                1,
                k,
                start,
                start + 500_000_000,
                value,
                0 if value is None else 12,
                start + 600_000_000,
            ).to_json(),
        )
    rec.close()
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=tmp_path / "none",
        record_dir=tmp_path / "records",
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        body = {"model": result.model, "format": "parquet", "source": "received"}
        r = c.post(URL, json=body, headers=h)
        assert r.status_code == 200, r.text
        assert 'filename="usv-received-2' in r.headers["content-disposition"]
        assert "1 empty windows" in r.headers["x-modd-notes"]
        none = c.post(URL, json=body | {"source": "archive"}, headers=h)
        assert none.status_code == 404
    (tmp_path / "r.parquet").write_bytes(r.content)
    table = pq.read_table(tmp_path / "r.parquet").to_pandas()
    with next((tmp_path / "records" / "usv").glob("*.mcap")).open("rb") as f:
        windows = [json.loads(m.data) for _s, _c, m in make_reader(f).iter_messages()]
    assert table["time"].astype("int64").tolist() == [w["end_ns"] for w in windows]
    assert table["value"].fillna(-1.0).tolist() == [
        -1.0 if w["value"] is None else w["value"] for w in windows
    ]
    assert set(table["topic"]) == {"avg"} and set(table["unit"]) == {"m s-2"}
