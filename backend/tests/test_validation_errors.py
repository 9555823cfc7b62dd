"""422 answers never echo the request: FastAPI's default put each error's
``input`` back into the answer, so a value JSON cannot carry (``1e400``
parses to infinity, a lone surrogate cannot be encoded) made the answer
itself fail with 500 on a dozen routes (subscriptions, backfill, replay...),
and an invalid body was echoed whole."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from .conftest import Headers

BODIES = [
    "1e400",
    '{"rate_bps": 1e400, "start_ns": -1e400}',
    '{"text": "\\ud800"}',
    '{"\\ud800": 1, "subscriber": "\\udfff"}',
    '["\\ud800", 1e400]',
]


@pytest.fixture
def body_routes(client: TestClient, admin: Headers, scenario1: str) -> list[tuple[str, str]]:
    pid = client.post(
        "/api/projects", headers=admin, json={"name": "p", "model": {"text": scenario1}}
    ).json()["id"]
    values = {
        "project_id": str(pid),
        "user_id": "1",
        "drone": "usv",
        "subscriber": "sub_1",
        "name": "x.mcap",
        "job_id": "1",
    }
    routes = []
    for path, ops in client.app.openapi()["paths"].items():  # type: ignore[attr-defined]
        for method, op in ops.items():
            if "requestBody" in op:
                for key, value in values.items():
                    path = path.replace("{" + key + "}", value)
                routes.append((method.upper(), path))
    assert len(routes) >= 15, routes
    return routes


def test_no_body_makes_an_answer_fail(
    client: TestClient, admin: Headers, body_routes: list[tuple[str, str]]
) -> None:
    raw = TestClient(client.app, raise_server_exceptions=False)  # a 500 is an answer here
    headers = {**admin, "Content-Type": "application/json"}
    for method, path in body_routes:
        for body in BODIES:
            r = raw.request(
                method, path, headers=headers, content=body.encode("utf-8", "surrogatepass")
            )
            assert r.status_code < 500 or r.status_code == 503, (method, path, body, r.text)
            json.loads(r.content)  # a JSON answer, whatever it says


def test_validation_errors_are_bounded_and_echo_nothing(
    client: TestClient, admin: Headers, tmp_path: Path
) -> None:
    secret = "do-not-echo-" + "x" * 1000
    body = {
        "username": 5,
        "password": [secret],
        "roles": "admin",
        **{f"extra{i}": secret for i in range(500)},
    }
    r = client.post("/api/users", headers=admin, json=body)
    assert r.status_code == 422
    errors = r.json()["detail"]
    assert 1 <= len(errors) <= 50 and {"type", "loc", "msg"} <= set(errors[0])
    assert secret not in r.text and len(r.content) < 20_000
