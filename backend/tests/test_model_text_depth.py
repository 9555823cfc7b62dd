"""A model given as JSON *text* (``format: json`` inside a JSON body, or the
raw import body) is parsed after the request guard, which sees only one
string: its nesting must be bounded where the text is parsed. Before, a
text 1,000 arrays deep raised RecursionError in ``json.loads`` and every
route that takes a model text answered 500 (docs/security.md, "HTTP and
WebSocket")."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend.roles import Role
from modd_model.io import load_file

from .conftest import Headers

DEPTHS = (1_000, 100_000)


def _deep_text(scenarios_dir: Path, depth: int) -> str:
    """A legal model's JSON with one extra property nested ``depth`` deep."""
    doc = load_file(scenarios_dir / "scenario1.modd").model
    assert doc is not None
    return (
        json.dumps(doc)[:-1]
        + ', "layout": {"nodes": {"n": {"x": '
        + "[" * depth
        + "]" * depth
        + ', "y": 1}}}}'
    )


def _state(client: TestClient, admin: Headers) -> tuple[Any, ...]:
    projects = client.get("/api/projects", headers=admin).json()
    versions = [
        len(client.get(f"/api/projects/{p['id']}/versions", headers=admin).json()) for p in projects
    ]
    return tuple(p["name"] for p in projects), tuple(versions)


@pytest.mark.parametrize("depth", DEPTHS)
def test_deep_json_model_text_is_a_located_error_on_every_text_route(
    client: TestClient, admin: Headers, scenarios_dir: Path, depth: int
) -> None:
    text = _deep_text(scenarios_dir, depth)
    legal = {"text": (scenarios_dir / "scenario1.modd").read_text()}
    pid = client.post("/api/projects", headers=admin, json={"name": "p", "model": legal}).json()[
        "id"
    ]
    before = _state(client, admin)
    as_text = {"text": text, "format": "json"}
    answers = {
        "validate": client.post("/api/validate", headers=admin, json=as_text),
        "plan": client.post("/api/plan", headers=admin, json=as_text),
        "create": client.post(
            "/api/projects", headers=admin, json={"name": "deep", "model": as_text}
        ),
        "save": client.put(
            f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, **as_text}
        ),
        # leading blanks: the guard does not take this body for JSON
        "import text": client.post(
            "/api/projects/import?name=deep_a&format=json",
            headers={**admin, "Content-Type": "text/plain"},
            content="\n " + text,
        ),
        "import bytes": client.post(
            "/api/projects/import?name=deep_b&format=json",
            headers={**admin, "Content-Type": "application/octet-stream"},
            content=("\n " + text).encode(),
        ),
    }
    for route, r in answers.items():
        assert r.status_code < 500, (route, r.status_code, r.text[:200])
        body = r.json()
        found = json.dumps(body)
        assert "nested" in found and "64" in found, (route, found[:300])
    assert answers["validate"].json()["ok"] is False
    assert answers["plan"].json()["ok"] is False
    assert _state(client, admin) == before  # nothing stored
    assert client.get(f"/api/projects/{pid}/model", headers=admin).status_code == 200
    assert client.get("/api/health").status_code == 200


BROKEN = [{}, {"drone": {"name": "usv"}}, {"text": "x", "format": "json"}]


@pytest.mark.parametrize("broken", BROKEN)
def test_every_read_of_an_invalid_revision_answers_without_a_500(
    client: TestClient,
    admin: Headers,
    user_factory: Callable[..., Headers],
    scenario1: str,
    broken: dict[str, Any],
) -> None:
    """An invalid model is stored (the workbench keeps work in progress), so
    every route that reads a revision must cope with any shape of it. Before,
    the Foxglove layout of such a revision answered 500 (KeyError)."""
    everyone = user_factory("all_roles", *(r.value for r in Role))
    pid = client.post(
        "/api/projects", headers=admin, json={"name": "p", "model": {"text": scenario1}}
    ).json()["id"]
    saved = client.put(
        f"/api/projects/{pid}/model", headers=everyone, json={"base_revision": 1, "model": broken}
    )
    assert saved.status_code == 200 and saved.json()["valid"] is False, saved.text
    spec = client.app.openapi()  # type: ignore[attr-defined]
    reads = [
        path.replace("{project_id}", str(pid)).replace("{target}", target)
        for path, ops in spec["paths"].items()
        if "get" in ops and "{project_id}" in path
        for target in (("integrator", "operator", "scientist") if "{target}" in path else ("",))
    ]
    assert len(reads) >= 8, reads
    for url in reads:
        r = client.get(url, headers=everyone)
        assert r.status_code < 500, (url, r.status_code, r.text[:200])
        r = client.get(url, headers=everyone, params={"revision": 2})
        assert r.status_code < 500, (url, r.status_code, r.text[:200])
