"""Downloads: each role's generated artefacts as a zip, from the generators'
own output; each role gets its own target only (admin any)."""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Callable
from pathlib import Path

from fastapi.testclient import TestClient
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, Headers, app_client, login


def _project(client: TestClient, admin: Headers, text: str) -> int:
    r = client.post("/api/projects", headers=admin, json={"name": "dl", "model": {"text": text}})
    return int(r.json()["id"])


def test_each_role_downloads_its_zip(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers], scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    people = {
        r: user_factory(f"dl_{r}", r) for r in ("integrator", "operator", "scientist", "designer")
    }
    for target in ("integrator", "operator", "scientist"):
        for role, h in people.items():
            r = client.get(f"/api/projects/{pid}/downloads/{target}", headers=h)
            assert r.status_code == (200 if role == target else 403), (role, target)
        r = client.get(f"/api/projects/{pid}/downloads/{target}", headers=admin)
        assert r.headers["content-type"] == "application/zip"
        names = zipfile.ZipFile(io.BytesIO(r.content)).namelist()
        assert names[0] == f"dl-r1-{target}/INDEX.txt"
        assert len(names) > 1
    ops = zipfile.ZipFile(
        io.BytesIO(client.get(f"/api/projects/{pid}/downloads/operator", headers=admin).content)
    )
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
    model["subscribers"][0]["aggregation"] = "MODE"
    client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": model}
    )
    bad = client.get(f"/api/projects/{pid}/downloads/scientist", headers=admin)
    assert bad.status_code == 422 and bad.json()["diagnostics"]
    ok = client.get(f"/api/projects/{pid}/downloads/scientist?revision=1", headers=admin)
    assert ok.status_code == 200
    assert client.get(f"/api/projects/{pid}/downloads/pilot", headers=admin).status_code == 422


def test_driver_readme_names_the_run_s_ingress_and_archive(tmp_path: Path, scenario1: str) -> None:
    """Behind `make run` (a `modd up` work dir: <run>/archive, <run>/ingress.sock)
    the integrator's drivers name that run's paths, not the model's defaults."""
    run = tmp_path / "run"
    (run / "archive").mkdir(parents=True)
    (run / "ingress.sock").touch()  # modd up's PubBroker socket (a plain file stands in)
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=run / "archive",
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        admin = login(c, "admin", ADMIN_PASSWORD)
        pid = _project(c, admin, scenario1)
        z = zipfile.ZipFile(
            io.BytesIO(c.get(f"/api/projects/{pid}/downloads/integrator", headers=admin).content)
        )
        readme = z.read(next(n for n in z.namelist() if n.endswith("README.md"))).decode()
        assert f"unix:{run / 'ingress.sock'}" in readme
        assert str(run / "archive") in readme
        assert "/tmp/modd/logs" not in readme


def test_a_remade_credential_is_announced_to_the_downloads_panel(tmp_path: Path) -> None:
    """A viewer.cred deleted by hand and made anew at the next start: the route the
    Downloads panel reads names it with when; before that, and with no station, nothing."""
    from modd.zenoh_auth import CredentialStore

    creds = tmp_path / "credentials"
    CredentialStore(creds).ensure()
    with app_client(tmp_path, zenoh_credentials=creds / "backend.cred") as c:
        assert c.get("/api/credentials/remade").status_code == 401
        admin = login(c, "admin", ADMIN_PASSWORD)
        assert c.get("/api/credentials/remade", headers=admin).json() == {"remade": []}
        (creds / "viewer.cred").unlink()
        CredentialStore(creds).ensure()
        notes = c.get("/api/credentials/remade", headers=admin).json()["remade"]
        assert [n["file"] for n in notes] == ["viewer.cred"]
        assert notes[0]["at"].endswith("Z")
        assert "viewer:" not in json.dumps(notes)  # no secret
