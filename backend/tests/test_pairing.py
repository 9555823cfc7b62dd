"""Pairing bundles from the workbench: an operator's (or admin's) only, in a POST body
with no-store headers; the drone's configuration and its link key sealed for that
drone; the station's key and the link key kept 0600 and reused; nothing logged."""

from __future__ import annotations

import io
import json
import logging
from collections.abc import Callable
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from modd.pairing.bundle import open_bundle, verify
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, Headers, login


def _project(client: TestClient, admin: Headers, text: str) -> int:
    r = client.post("/api/projects", headers=admin, json={"name": "pair", "model": {"text": text}})
    return int(r.json()["id"])


def test_only_an_operator_makes_a_bundle_with_no_store(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers], scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    for role in ("designer", "scientist", "integrator"):
        h = user_factory(f"p_{role}", role)
        assert client.post(f"/api/projects/{pid}/pairing", headers=h, json={}).status_code == 403
    op = user_factory("p_operator", "operator")
    r = client.post(f"/api/projects/{pid}/pairing", headers=op, json={})
    assert r.status_code == 200, r.text
    assert r.headers["cache-control"] == "no-store"
    body = r.json()
    assert body["drone"] == "usv" and body["filename"] == "usv.modd-pair"
    assert client.get(f"/api/projects/{pid}/pairing", headers=op).status_code == 405


def test_bundle_carries_the_drone_s_files_and_its_link_key(
    tmp_path: Path, scenario1: str, caplog: pytest.LogCaptureFixture
) -> None:
    settings = Settings(
        data_dir=tmp_path / "data", zenoh_enabled=False, initial_admin_password=ADMIN_PASSWORD
    )
    caplog.set_level(logging.DEBUG)
    out = io.StringIO()
    with TestClient(create_app(settings, out=out)) as c:
        admin = login(c, "admin", ADMIN_PASSWORD)
        pid = _project(c, admin, scenario1)
        first = c.post(f"/api/projects/{pid}/pairing", headers=admin, json={}).json()
        again = c.post(f"/api/projects/{pid}/pairing", headers=admin, json={"revision": 1}).json()
        operator = c.get(f"/api/projects/{pid}/downloads/operator", headers=admin)
    key_file = Path(first["link_key_file"])
    assert key_file == tmp_path / "data" / "pairing" / "link-keys" / "usv.key"
    assert key_file.stat().st_mode & 0o777 == 0o600
    station = tmp_path / "data" / "pairing" / "station.key"
    assert station.stat().st_mode & 0o777 == 0o600
    opened = open_bundle(
        first["bundle"].encode(), first["code"], verify(first["bundle"].encode()).issued_ns
    )
    assert opened.files["link.key"] == key_file.read_text().strip()
    assert opened.files["pubbroker.json"]["name"] == "usv"
    assert opened.files["model.json"]["drone"]["name"] == "usv"
    # the same station key and link key; a new code and new bytes each time
    assert again["fingerprint"] == first["fingerprint"] and again["code"] != first["code"]
    assert again["link_key_file"] == first["link_key_file"] and again["bundle"] != first["bundle"]
    assert operator.status_code == 200
    logged = out.getvalue() + caplog.text
    for secret in (first["code"], first["code"].replace("-", ""), opened.files["link.key"]):
        assert secret not in logged
    assert json.loads(first["bundle"])["drone"] == "usv"
    assert first["code"] not in first["bundle"]


def test_invalid_revision_is_refused(client: TestClient, admin: Headers, scenario1: str) -> None:
    pid = _project(client, admin, scenario1)
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    model["subscribers"][0]["aggregation"] = "MODE"
    client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": model}
    )
    bad = client.post(f"/api/projects/{pid}/pairing", headers=admin, json={})
    assert bad.status_code == 422 and "fix them before pairing" in bad.json()["detail"]
