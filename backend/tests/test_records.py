"""The base-station records (written by the SubBroker's BaseRecord) listed and
downloaded beside the drone's archives; paths confined to the drone's folder."""

from __future__ import annotations

import io
from pathlib import Path

from fastapi.testclient import TestClient
from modd.subbroker.payload import DeliveredValue
from modd.subbroker.record import BaseRecord
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, login


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
