"""The base-station records (written by the SubBroker's BaseRecord) listed and
downloaded beside the drone's archives; paths confined to the drone's folder."""

from __future__ import annotations

import io
from pathlib import Path

from fastapi.testclient import TestClient
from modd.subbroker.payload import DeliveredValue
from modd.subbroker.record import BaseRecord
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, app_client, login


def test_records_listed_and_downloaded(tmp_path: Path) -> None:
    rec = BaseRecord(tmp_path / "records", "usv")
    rec.begin("scenario1", 1_795_000_000_000_000_000)
    for i in range(4):
        v = DeliveredValue(
            "sub_5",
            "usv.a.z",
            "MIN",
            "0.25",
            "M",
            1,
            i,
            i * 250,
            i * 250 + 250,
            -0.5,
            None,
            9,
            backfilled=i == 2,
        )
        rec.put("sub_5", v.to_json())
    rec.close()
    (tmp_path / "secret.mcap").write_bytes(b"x")
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        record_dir=tmp_path / "records",
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        files = c.get("/api/drones/usv/records", headers=h).json()
        assert len(files) == 1 and files[0]["complete"]
        assert files[0]["topics"] == [{"topic": "modd/usv/sub/sub_5", "messages": 4}]
        got = c.get(f"/api/drones/usv/records/{files[0]['name']}", headers=h)
        assert got.status_code == 200 and got.content[:5] == b"\x89MCAP"
        assert c.get("/api/drones/usv/records/..%2Fsecret.mcap", headers=h).status_code == 404
        assert c.get("/api/drones/usv/records").status_code == 401


def _fix(sub: str, topic: str, i: int, value: float, t0: int) -> bytes:
    end = t0 + (i + 1) * 1_000_000_000
    v = DeliveredValue(sub, topic, "LAST", "1", "M", 1, i, end - 10**9, end, value, None, 1)
    return v.to_json()


def test_the_track_since_the_mission_began_thinned_and_paired(tmp_path: Path) -> None:
    """The Map's whole track after a reload: the lat/lon subscribers' windows of the
    newest record, paired by time and thinned to the points asked; every point
    checked against the file read with the official mcap reader."""
    import json

    from mcap.reader import make_reader

    t0 = 1_795_000_000_000_000_000
    rec = BaseRecord(tmp_path / "records", "usv")
    rec.begin("survey", t0)
    for i in range(300):
        rec.put("sub_lat", _fix("sub_lat", "usv.gps.latitude", i, 44.6 + i * 1e-5, t0))
        if i != 7:  # a longitude missing: that latitude is no fix
            rec.put("sub_lon", _fix("sub_lon", "usv.gps.longitude", i, -63.5 - i * 1e-5, t0))
        if i % 2 == 0:  # the colour subscriber every other window
            rec.put("sub_temp", _fix("sub_temp", "usv.ctd.water_temperature", i, 10 + i / 10, t0))
    rec.close()
    assert rec.path is not None
    oracle: dict[str, dict[int, float]] = {"sub_lat": {}, "sub_lon": {}, "sub_temp": {}}
    with open(rec.path, "rb") as f:
        for _, ch, msg in make_reader(f).iter_messages():
            oracle[ch.topic.rsplit("/", 1)[1]][msg.log_time] = json.loads(msg.data)["value"]
    with app_client(tmp_path, record_dir=tmp_path / "records") as c:
        h = login(c, "admin", ADMIN_PASSWORD)
        url = "/api/drones/usv/track?lat=sub_lat&lon=sub_lon"
        got = c.get(f"{url}&points=50", headers=h).json()
        assert got["file"] == rec.path.name and got["total"] == 299
        pts = got["points"]
        assert len(pts) == 50
        assert pts[0][0] == (t0 + 10**9) / 1e9 and pts[-1][0] == (t0 + 300 * 10**9) / 1e9
        for t, lat, lon in pts:
            ns = round(t * 1e9 / 1e6) * 1_000_000
            assert lat == oracle["sub_lat"][ns] and lon == oracle["sub_lon"][ns]
        assert all(a[0] < b[0] for a, b in zip(pts, pts[1:], strict=False))
        assert len(c.get(url, headers=h).json()["points"]) == 299
        coloured = c.get(f"{url}&points=50&colour=sub_temp", headers=h).json()["points"]
        assert [p[:3] for p in coloured] == pts
        for t, _, _, v in coloured:
            ns = round(t * 1e9 / 1e6) * 1_000_000
            assert v == oracle["sub_temp"].get(ns)  # None where it had no window then
        assert c.get(f"{url}&points=100000", headers=h).status_code == 422
        assert c.get("/api/drones/usv/track?lat=a.b&lon=x", headers=h).status_code == 422
        none = c.get("/api/drones/other/track?lat=sub_lat&lon=sub_lon", headers=h).json()
        assert none == {"file": None, "total": 0, "points": []}
        assert c.get(url).status_code == 401
