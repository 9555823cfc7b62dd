"""The hot routes' one store hop (deps.in_store, issue 41): sessions,
roles, answers and the diagnostics kept of stored models, checked against
modd_model's own validation and the response models' fields."""

from __future__ import annotations

import json
from datetime import timedelta

from fastapi.testclient import TestClient
from modd_backend import versions
from modd_backend.modelio import canonical_json, diagnostics_json
from modd_backend.schemas import ModelOut, VersionOut
from modd_backend.tables import Session, utcnow
from modd_model import validate
from sqlalchemy import update

from .conftest import Headers


def _project(client: TestClient, admin: Headers, text: str) -> int:
    r = client.post("/api/projects", headers=admin, json={"name": "p", "model": {"text": text}})
    assert r.status_code in (200, 201), r.text
    pid: int = r.json()["id"]
    return pid


def test_expired_session_is_refused_by_every_route(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    assert client.get(f"/api/projects/{pid}/model", headers=admin).status_code == 200
    store = client.app.state.modd.store  # type: ignore[attr-defined]
    with store.session() as db:
        db.execute(update(Session).values(expires_at=utcnow() - timedelta(seconds=1)))
        db.commit()
    for path in (f"/api/projects/{pid}/model", f"/api/projects/{pid}/versions", "/api/auth/me"):
        r = client.get(path, headers=admin)
        assert r.status_code == 401, (path, r.text)
        assert r.headers["www-authenticate"] == "Bearer"
    r = client.put(f"/api/projects/{pid}/model", headers=admin, json={"model": {}})
    assert r.status_code == 401


def test_answers_are_the_response_models_with_modd_models_diagnostics(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    head = client.get(f"/api/projects/{pid}/model", headers=admin)
    assert head.headers["content-type"] == "application/json"
    model = head.json()["model"]
    broken = {**model, "link": {**(model.get("link") or {}), "maxBuffer": -5}}
    r = client.put(
        f"/api/projects/{pid}/model",
        headers=admin,
        json={"model": broken, "base_revision": head.json()["revision"]},
    )
    assert r.status_code == 200, r.text
    saved = r.json()
    assert set(saved) == set(ModelOut.model_fields)
    want = diagnostics_json(validate(json.loads(canonical_json(broken))))
    given = [{k: v for k, v in d.items() if v is not None} for d in saved["diagnostics"]]
    assert given == want and want, want
    assert saved["valid"] == (not any(d["severity"] == "error" for d in want))
    again = client.get(f"/api/projects/{pid}/model", headers=admin).json()
    assert again == saved
    listed = client.get(f"/api/projects/{pid}/versions", headers=admin).json()
    assert [v["revision"] for v in listed] == [saved["revision"], saved["revision"] - 1]
    assert all(set(v) == set(VersionOut.model_fields) for v in listed)


def test_missing_project_and_revision_are_404(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    r = client.get(f"/api/projects/{pid + 1000}/model", headers=admin)
    assert r.status_code == 404 and f"no project {pid + 1000}" in r.text
    r = client.get(f"/api/projects/{pid}/model?revision=99", headers=admin)
    assert r.status_code == 404 and "has no revision 99" in r.text


def test_a_role_without_edit_rights_is_refused_before_the_body_is_read(
    client: TestClient, admin: Headers, user_factory: object, scenario1: str
) -> None:
    pid = _project(client, admin, scenario1)
    viewer = user_factory("watcher", "operator")  # type: ignore[operator]
    r = client.put(f"/api/projects/{pid}/model", headers=viewer, content=b"not json")
    assert r.status_code == 403 and "this needs the role" in r.text


def test_diagnostics_cache_matches_validation_and_stays_bounded() -> None:
    versions._diagnostics.clear()
    docs = [canonical_json({"name": f"m{i}", "link": {"maxBuffer": -i}}) for i in range(300)]
    for doc in docs:
        assert versions.diagnostics_of(doc) == diagnostics_json(validate(json.loads(doc)))
    assert len(versions._diagnostics) == versions._CACHED
    big = canonical_json({"name": "x" * (versions._CACHED_CHARS + 1)})
    assert versions.diagnostics_of(big) == diagnostics_json(validate(json.loads(big)))
    assert big not in versions._diagnostics
    first = versions.diagnostics_of(docs[-1])
    first.clear()  # a caller's copy: the kept diagnostics stay whole
    assert versions.diagnostics_of(docs[-1]) == diagnostics_json(validate(json.loads(docs[-1])))
