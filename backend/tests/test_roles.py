"""Each role's allow/deny matrix: model edits by the part they change,
project creation and deletion, user management. (Deploy: test_deploy.py.)"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import pytest
from fastapi.testclient import TestClient

from .conftest import Headers

ROLES = ("designer", "integrator", "scientist", "operator", "admin")


# Each edit takes a number so that every role's attempt changes something.
def _edit_drone(m: dict[str, Any], i: int) -> None:
    m["drone"]["description"] = f"platform {i}"


def _edit_pubbroker(m: dict[str, Any], i: int) -> None:
    m["pubBroker"]["endpoint"]["port"] = 7900 + i


def _edit_subbroker(m: dict[str, Any], i: int) -> None:
    m["subBroker"]["configPath"] = f"/tmp/conf{i}"


def _edit_link(m: dict[str, Any], i: int) -> None:
    m["link"] = {"maxBuffer": 100 + i}


def _edit_publishers(m: dict[str, Any], i: int) -> None:
    m["publishers"][0]["periodS"] = f"0.0{i + 1}"


def _edit_sensors(m: dict[str, Any], i: int) -> None:
    m["drone"]["sensors"][0]["variables"].append({"name": f"temp{i}", "unit": "DEGREE_CELSIUS"})


def _edit_variable(m: dict[str, Any], i: int) -> None:
    m["drone"]["sensors"][0]["variables"][0]["description"] = f"x axis {i}"


def _edit_subscribers(m: dict[str, Any], i: int) -> None:
    m["subscribers"][0]["periodS"] = str(4 + i)


def _edit_layout(m: dict[str, Any], i: int) -> None:
    m["layout"] = {"nodes": {"drone": {"x": 10 + i, "y": 20}}}


#: (edit, the roles allowed to make it)
EDITS = {
    "drone": (_edit_drone, {"designer", "admin"}),
    "pubBroker": (_edit_pubbroker, {"designer", "admin"}),
    "subBroker": (_edit_subbroker, {"designer", "admin"}),
    "link": (_edit_link, {"designer", "admin"}),
    "publishers": (_edit_publishers, {"designer", "admin"}),
    "sensors": (_edit_sensors, {"integrator", "admin"}),
    "variable": (_edit_variable, {"integrator", "admin"}),
    "subscribers": (_edit_subscribers, {"scientist", "admin"}),
    "layout": (_edit_layout, {"designer", "integrator", "scientist", "admin"}),
}


@pytest.fixture
def users(user_factory: Callable[..., Headers], admin: Headers) -> dict[str, Headers]:
    out = {r: user_factory(f"user_{r}", r) for r in ROLES if r != "admin"}
    out["admin"] = admin
    return out


@pytest.fixture
def project(client: TestClient, admin: Headers, scenario1: str) -> int:
    r = client.post(
        "/api/projects", headers=admin, json={"name": "matrix", "model": {"text": scenario1}}
    )
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


@pytest.mark.parametrize("part", sorted(EDITS))
def test_model_edit_matrix(
    client: TestClient, users: dict[str, Headers], project: int, part: str
) -> None:
    edit, allowed = EDITS[part]
    for i, role in enumerate(ROLES):
        head = client.get(f"/api/projects/{project}/model", headers=users[role]).json()
        model = copy.deepcopy(head["model"])
        edit(model, i)
        r = client.put(
            f"/api/projects/{project}/model",
            headers=users[role],
            json={
                "base_revision": head["revision"],
                "model": model,
                "message": f"{role} edits {part}",
            },
        )
        expected = 200 if role in allowed else 403
        assert r.status_code == expected, (role, part, r.text)
        if expected == 403 and role != "operator":  # an editor: told which part is whose
            assert r.json()["denied"][0]["role"] in {"designer", "integrator", "scientist"}


def test_mixed_edit_needs_every_owning_role(
    client: TestClient,
    users: dict[str, Headers],
    project: int,
    user_factory: Callable[..., Headers],
) -> None:
    head = client.get(f"/api/projects/{project}/model", headers=users["scientist"]).json()
    model = copy.deepcopy(head["model"])
    _edit_subscribers(model, 0)
    _edit_sensors(model, 0)
    body = {"base_revision": head["revision"], "model": model}
    r = client.put(f"/api/projects/{project}/model", headers=users["scientist"], json=body)
    assert r.status_code == 403
    assert r.json()["denied"] == [{"part": "/drone/sensors", "role": "integrator"}]
    both = user_factory("both", "scientist", "integrator")
    assert client.put(f"/api/projects/{project}/model", headers=both, json=body).status_code == 200


def test_project_matrix(
    client: TestClient, users: dict[str, Headers], scenario1: str, project: int
) -> None:
    for role in ROLES:
        h = users[role]
        assert client.get("/api/projects", headers=h).status_code == 200
        assert client.get(f"/api/projects/{project}/model", headers=h).status_code == 200
        empty = client.post("/api/projects", headers=h, json={"name": f"empty_{role}"})
        assert empty.status_code == (403 if role == "operator" else 201), role
        full = client.post(
            "/api/projects", headers=h, json={"name": f"full_{role}", "model": {"text": scenario1}}
        )
        # A whole model spans every editing role's parts: only admin holds them all.
        assert full.status_code == (201 if role == "admin" else 403), role
    for role in ROLES:
        r = client.delete(f"/api/projects/{project}", headers=users[role])
        assert r.status_code == (204 if role == "admin" else 403), role
