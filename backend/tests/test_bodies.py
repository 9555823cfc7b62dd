"""The routes that take a model read their body off the event loop
(modd_backend.bodies): in the thread pool, with FastAPI's answers kept
(422 in FastAPI's form, the schemas in the OpenAPI description)."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend import bodies

from .conftest import Headers


def _on_loop() -> bool:
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return False
    return True


def test_model_bodies_are_read_off_the_event_loop(
    client: TestClient, admin: Headers, scenario1: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: list[tuple[str, bool]] = []
    read_as = bodies.read_as

    def recording(body: bytes, is_json: bool, cls: type[Any]) -> Any:
        seen.append((cls.__name__, _on_loop()))
        return read_as(body, is_json, cls)

    monkeypatch.setattr(bodies, "read_as", recording)
    r = client.post(
        "/api/projects", headers=admin, json={"name": "offloop", "model": {"text": scenario1}}
    )
    assert r.status_code == 201, r.text
    pid = r.json()["id"]
    assert client.post("/api/validate", headers=admin, json={"text": scenario1}).json()["ok"]
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    r = client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": model}
    )
    assert r.status_code == 200, r.text
    assert seen == [("ProjectIn", False), ("ModelInput", False), ("SaveIn", False)]


@pytest.mark.parametrize(
    ("content", "kinds"),
    [
        (b"{not json", {"json_invalid"}),
        (b"", {"missing"}),
        (b'{"model": {}, "text": "x"}', {"value_error", "missing"}),  # missing: name, base_revision
        (b"[1]", {"model_type"}),
    ],
)
def test_a_body_that_is_not_the_model_is_fastapis_422(
    client: TestClient, admin: Headers, content: bytes, kinds: set[str]
) -> None:
    for method, url in (
        ("POST", "/api/validate"),
        ("PUT", "/api/projects/1/model"),
        ("POST", "/api/projects"),
    ):
        r = client.request(
            method, url, headers={**admin, "content-type": "application/json"}, content=content
        )
        assert r.status_code == 422, (url, r.text)
        detail = r.json()["detail"]
        assert detail[0]["loc"][0] == "body", (url, r.text)
        assert {d["type"] for d in detail} <= kinds, (url, r.text)


def test_the_bodies_schemas_are_in_the_openapi_description(client: TestClient) -> None:
    spec = client.get("/openapi.json").json()
    schemas = spec["components"]["schemas"]
    for path, method, name in (
        ("/api/validate", "post", "ModelInput"),
        ("/api/projects/{project_id}/model", "put", "SaveIn"),
        ("/api/projects", "post", "ProjectIn"),
        ("/api/plan", "post", "ModelInput"),
    ):
        body = spec["paths"][path][method]["requestBody"]["content"]["application/json"]
        assert body["schema"]["$ref"] == f"#/components/schemas/{name}"
        assert "properties" in schemas[name]
    assert schemas["ProjectIn"]["properties"]["model"]["anyOf"][0]["$ref"].endswith("/ModelInput")
    assert set(schemas["SaveIn"]["required"]) == {"base_revision"}
