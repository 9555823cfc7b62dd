"""Held-out attacks of the kinds the security review found, over every route
of the OpenAPI description rather than the ones the findings named: no route
answers without a session, a cookie session without the CSRF header cannot
change anything, a user without a role changes nothing, every body-taking
route refuses an oversized (413) or over-deep (422) body and stores nothing,
and every answer carries the security headers."""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD, login

#: Routes that answer without a session.
PUBLIC = {("GET", "/api/health"), ("POST", "/api/auth/login")}
#: Routes any logged-in user may use: their own session, and computations
#: that store nothing.
OWN_OR_STATELESS = {
    ("POST", "/api/auth/logout"),
    ("PUT", "/api/auth/password"),
    ("POST", "/api/validate"),
    ("POST", "/api/print"),
    ("POST", "/api/plan"),
}
UNSAFE = {"POST", "PUT", "PATCH", "DELETE"}


@pytest.fixture(scope="module")
def world(
    tmp_path_factory: pytest.TempPathFactory, scenarios_dir: Path
) -> Iterator[dict[str, Any]]:
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("sweep") / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        max_body_bytes=256 * 1024,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        admin = login(c, "admin", ADMIN_PASSWORD)
        text = (scenarios_dir / "scenario1.modd").read_text()
        pid = c.post(
            "/api/projects", headers=admin, json={"name": "p", "model": {"text": text}}
        ).json()["id"]
        users = {}
        for name, roles in (("nobody", []), ("victim", ["designer"])):
            r = c.post(
                "/api/users",
                headers=admin,
                json={"username": name, "password": f"pw-{name}-12345", "roles": roles},
            )
            users[name] = r.json()["id"]
        openapi = c.app.openapi()  # type: ignore[attr-defined]
        yield {
            "c": c,
            "admin": admin,
            "pid": pid,
            "users": users,
            "nobody": login(c, "nobody", "pw-nobody-12345"),
            "ops": _operations(openapi, pid, users["victim"]),
        }


def _operations(spec: dict[str, Any], pid: int, uid: int) -> list[tuple[str, str, bool]]:
    values = {
        "project_id": str(pid),
        "user_id": str(uid),
        "drone": "usv",
        "subscriber": "sub_1",
        "name": "x.mcap",
        "target": "cpp-driver",
        "job_id": "1",
        "revision": "1",
        "z": "1",
        "x": "0",
        "y": "0",
        "ext": "png",
    }
    out = []
    for path, ops in spec["paths"].items():
        for method, op in ops.items():
            url = path
            for key, value in values.items():
                url = url.replace("{" + key + "}", value)
            assert "{" not in url, f"no value for a parameter of {path}"
            out.append((method.upper(), url if url != path else path, "requestBody" in op))
    assert len(out) >= 30
    return out


def _state(w: dict[str, Any]) -> Any:
    c, admin = w["c"], w["admin"]
    versions = c.get(f"/api/projects/{w['pid']}/versions", headers=admin).json()
    users = c.get("/api/users", headers=admin).json()
    projects = c.get("/api/projects", headers=admin).json()
    return (
        len(versions),
        sorted((u["username"], tuple(u["roles"])) for u in users),
        sorted(p["name"] for p in projects),
    )


def _path_of(url: str, w: dict[str, Any]) -> str:
    return url.replace(f"/{w['pid']}", "/{project_id}")


def test_no_route_answers_without_a_session(world: dict[str, Any]) -> None:
    c = world["c"]
    for method, url, _ in world["ops"]:
        if (method, url) in PUBLIC:
            continue
        r = c.request(method, url, json={} if method in UNSAFE else None)
        assert r.status_code == 401, (method, url, r.status_code)
        assert "frame-ancestors" in r.headers["content-security-policy"]
        assert r.headers["x-content-type-options"] == "nosniff"


def test_cookie_without_csrf_header_changes_nothing(world: dict[str, Any]) -> None:
    c = world["c"]
    r = c.post(
        "/api/auth/login",
        json={"username": "admin", "password": ADMIN_PASSWORD, "session": "cookie"},
    )
    cookie = r.cookies["modd_session"]
    c.cookies.clear()
    before = _state(world)
    for method, url, _ in world["ops"]:
        if method not in UNSAFE or (method, url) in PUBLIC:
            continue
        r = c.request(method, url, json={}, headers={"Cookie": f"modd_session={cookie}"})
        assert r.status_code == 403, (method, url, r.status_code)
    assert _state(world) == before


def test_a_user_without_a_role_changes_nothing(world: dict[str, Any]) -> None:
    c = world["c"]
    before = _state(world)
    model = c.get(f"/api/projects/{world['pid']}/model", headers=world["admin"]).json()
    bodies: dict[str, Any] = {
        "/api/users": {"username": "evil", "password": "pw-evil-12345", "roles": ["admin"]},
        f"/api/users/{world['users']['victim']}": {"roles": ["admin"]},
        "/api/projects": {"name": "q", "model": model["model"]},
        f"/api/projects/{world['pid']}/model": {"base_revision": 1, "model": model["model"]},
        f"/api/projects/{world['pid']}/deployments": {"revision": 1},
        "/api/drones/usv/subscriptions": {
            "topic": "usv.a.b",
            "period_s": "1",
            "aggregation": "MIN",
        },
        "/api/scene/usv/colour": {"subscriber": None},
    }
    for method, url, _ in world["ops"]:
        if method not in UNSAFE or (method, url) in PUBLIC | OWN_OR_STATELESS:
            continue
        r = c.request(method, url, json=bodies.get(url, {}), headers=world["nobody"])
        assert not 200 <= r.status_code < 300, (method, url, r.status_code, r.text[:200])
    assert _state(world) == before


def test_every_body_route_refuses_oversized_and_overdeep_bodies(world: dict[str, Any]) -> None:
    c = world["c"]
    before = _state(world)
    deep = "[" * 200 + "]" * 200
    for method, url, has_body in world["ops"]:
        if not has_body:
            continue
        big = c.request(
            method,
            url,
            content=b'{"x": "' + b"a" * 300_000 + b'"}',
            headers={**world["admin"], "Content-Type": "application/json"},
        )
        assert big.status_code == 413, (method, url, big.status_code)
        nested = c.request(
            method,
            url,
            content=deep.encode(),
            headers={**world["admin"], "Content-Type": "application/json"},
        )
        assert nested.status_code == 422 and "nested" in nested.json()["detail"], (method, url)
        assert "frame-ancestors 'none'" in nested.headers["content-security-policy"]
    assert _state(world) == before
