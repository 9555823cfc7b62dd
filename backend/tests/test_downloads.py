"""Downloads: each role's generated artefacts as a zip, from the generators'
own output; each role gets its own target only (admin any)."""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Callable

from fastapi.testclient import TestClient

from .conftest import Headers


def _project(client: TestClient, admin: Headers, text: str) -> int:
    r = client.post("/api/projects", headers=admin, json={"name": "dl", "model": {"text": text}})
    return int(r.json()["id"])


def test_each_role_downloads_its_zip(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers], scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    people = {r: user_factory(f"dl_{r}", r) for r in ("integrator", "operator", "scientist",
                                                      "designer")}
    for target in ("integrator", "operator", "scientist"):
        for role, h in people.items():
            r = client.get(f"/api/projects/{pid}/downloads/{target}", headers=h)
            assert r.status_code == (200 if role == target else 403), (role, target)
        r = client.get(f"/api/projects/{pid}/downloads/{target}", headers=admin)
        assert r.headers["content-type"] == "application/zip"
        names = zipfile.ZipFile(io.BytesIO(r.content)).namelist()
        assert names[0] == f"dl-r1-{target}/INDEX.txt"
        assert len(names) > 1
    ops = zipfile.ZipFile(io.BytesIO(
        client.get(f"/api/projects/{pid}/downloads/operator", headers=admin).content))
    pb = next(n for n in ops.namelist() if n.endswith("pubbroker.json"))
    cfg = json.loads(ops.read(pb))
    sizes = {t["name"]: t["buffer_size"] for t in cfg["topics"]}
    assert sizes["usv.accelerometer.accel_z"] == 6  # the planner's numbers, via the generators
    again = client.get(f"/api/projects/{pid}/downloads/operator", headers=admin).content
    assert again == client.get(f"/api/projects/{pid}/downloads/operator", headers=admin).content


def test_invalid_revision_and_unknown_target(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    model["subscribers"][0]["aggregation"] = "MEDIAN"
    client.put(f"/api/projects/{pid}/model", headers=admin,
               json={"base_revision": 1, "model": model})
    bad = client.get(f"/api/projects/{pid}/downloads/scientist", headers=admin)
    assert bad.status_code == 422 and bad.json()["diagnostics"]
    ok = client.get(f"/api/projects/{pid}/downloads/scientist?revision=1", headers=admin)
    assert ok.status_code == 200
    assert client.get(f"/api/projects/{pid}/downloads/pilot", headers=admin).status_code == 422
