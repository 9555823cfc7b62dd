"""The models API on a real SQLite file: versions, optimistic concurrency,
import/export, structured validation errors."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from fastapi.testclient import TestClient
from modd_model import dumps, load_text

from .conftest import Headers


def _create(client: TestClient, h: Headers, text: str, name: str = "p") -> int:
    r = client.post("/api/projects", headers=h, json={"name": name, "model": {"text": text}})
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


def test_create_read_and_versions(client: TestClient, admin: Headers, scenario1: str) -> None:
    pid = _create(client, admin, scenario1)
    got = client.get(f"/api/projects/{pid}/model", headers=admin).json()
    assert got["revision"] == 1 and got["valid"] and got["diagnostics"] == []
    assert got["model"] == load_text(scenario1, "s1.modd").model
    assert got["author"] == "admin"
    assert client.get(f"/api/projects/{pid}", headers=admin).json()["head_revision"] == 1
    model = got["model"]
    model["subscribers"][0]["periodS"] = "4"
    r = client.put(
        f"/api/projects/{pid}/model",
        headers=admin,
        json={"base_revision": 1, "model": model, "message": "slower"},
    )
    assert r.status_code == 200 and r.json()["revision"] == 2
    versions = client.get(f"/api/projects/{pid}/versions", headers=admin).json()
    assert [(v["revision"], v["message"]) for v in versions] == [(2, "slower"), (1, "created")]
    old = client.get(f"/api/projects/{pid}/model?revision=1", headers=admin).json()
    assert old["model"]["subscribers"][0]["periodS"] == "2.0"
    assert client.get(f"/api/projects/{pid}/model?revision=9", headers=admin).status_code == 404
    assert client.get("/api/projects/999/model", headers=admin).status_code == 404


def test_stale_save_gets_409_with_current_revision(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    pid = _create(client, admin, scenario1)
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    first = dict(model, link={"maxBuffer": 500})
    assert (
        client.put(
            f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": first}
        ).status_code
        == 200
    )
    second = dict(model, link={"maxBuffer": 400})
    r = client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": second}
    )
    assert r.status_code == 409
    assert r.json()["current_revision"] == 2
    head = client.get(f"/api/projects/{pid}/model", headers=admin).json()
    assert head["model"]["link"] == {"maxBuffer": 500}  # the first save is kept


def test_syntax_error_is_located(client: TestClient, admin: Headers, scenario1: str) -> None:
    pid = _create(client, admin, scenario1)
    broken = scenario1.replace("Publishers {", "Publishers {{")
    r = client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "text": broken}
    )
    assert r.status_code == 422
    diag = r.json()["diagnostics"][0]
    assert diag["severity"] == "error" and diag["line"] > 1 and diag["col"] >= 1
    assert client.get(f"/api/projects/{pid}", headers=admin).json()["head_revision"] == 1


def test_text_diagnostics_reach_the_client_with_their_end(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    bad = scenario1.replace("AVERAGE)", "AVERAGED)", 1)
    r = client.post("/api/validate", headers=admin, json={"text": bad})
    diags = [d for d in r.json()["diagnostics"] if d["pointer"].endswith("/aggregation")]
    assert len(diags) == 1, r.json()
    d = diags[0]
    line = bad.splitlines()[d["line"] - 1]
    assert d["end_line"] == d["line"] and line[d["col"] - 1 : d["end_col"] - 1] == "AVERAGED"


def test_invalid_model_is_saved_with_pointed_diagnostics(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    pid = _create(client, admin, scenario1)
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    model["subscribers"][1]["aggregation"] = "MODE"
    r = client.put(
        f"/api/projects/{pid}/model",
        headers=admin,
        json={"base_revision": 1, "model": model, "message": "wip"},
    )
    assert r.status_code == 200  # work in progress is never lost
    body = r.json()
    assert body["valid"] is False
    pointers = {d["pointer"] for d in body["diagnostics"]}
    assert any(p.startswith("/subscribers/1") for p in pointers), pointers


def test_text_save_keeps_layout(client: TestClient, admin: Headers, scenario1: str) -> None:
    pid = _create(client, admin, scenario1)
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    model["layout"] = {"nodes": {"drone": {"x": 1.5, "y": 2}}}
    client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": model}
    )
    edited = scenario1.replace("2.0, AVERAGE", "4.0, AVERAGE")
    r = client.put(
        f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 2, "text": edited}
    )
    assert r.status_code == 200
    assert r.json()["model"]["layout"] == model["layout"]
    assert r.json()["model"]["subscribers"][0]["periodS"] == "4.0"


def test_import_and_export_both_notations(
    client: TestClient, user_factory: Callable[..., Headers], admin: Headers, scenario1: str
) -> None:
    r = client.post(
        "/api/projects/import",
        params={"name": "imported", "format": "modd"},
        headers={**admin, "Content-Type": "text/plain"},
        content=scenario1.encode(),
    )
    assert r.status_code == 201, r.text
    pid = r.json()["id"]
    text = client.get(f"/api/projects/{pid}/export?format=modd", headers=admin)
    assert text.status_code == 200
    assert "attachment" in text.headers["content-disposition"]
    assert load_text(text.text, "x.modd").model == load_text(scenario1, "s.modd").model
    js = client.get(f"/api/projects/{pid}/export?format=json", headers=admin)
    doc: dict[str, Any] = json.loads(js.text)
    r = client.post(
        "/api/projects/import",
        params={"name": "again", "format": "json"},
        headers={**admin, "Content-Type": "application/json"},
        content=js.content,
    )
    assert r.status_code == 201
    again = client.get(f"/api/projects/{r.json()['id']}/model", headers=admin).json()["model"]
    assert again == doc
    bad = client.post(
        "/api/projects/import",
        params={"name": "bad", "format": "json"},
        headers=admin,
        content=b"{not json",
    )
    assert bad.status_code == 422
    assert bad.json()["diagnostics"][0]["line"] == 1
    binary = client.post(
        "/api/projects/import", params={"name": "bin"}, headers=admin, content=b"\xff\xfe\x00"
    )
    assert binary.status_code == 422
    dup = client.post(
        "/api/projects/import",
        params={"name": "again", "format": "json"},
        headers=admin,
        content=js.content,
    )
    assert dup.status_code == 409


def test_validate_endpoint(client: TestClient, admin: Headers, scenario1: str) -> None:
    ok = client.post("/api/validate", headers=admin, json={"text": scenario1}).json()
    assert ok["ok"] and ok["model"]["drone"]["name"] == "usv"
    bad = client.post(
        "/api/validate", headers=admin, json={"text": scenario1.replace("MIN", "MEAN")}
    ).json()
    assert not bad["ok"]
    d = bad["diagnostics"][0]
    assert "MEAN" in d["message"] and d["line"] and d["pointer"].startswith("/subscribers/")
    both = client.post("/api/validate", headers=admin, json={"text": "x", "model": {}})
    assert both.status_code == 422


def test_print_follows_an_unsaved_model(client: TestClient, admin: Headers, scenario1: str) -> None:
    """The text view of unsaved diagram edits: print what the editor holds."""
    model = client.post("/api/validate", json={"text": scenario1}, headers=admin).json()["model"]
    model["subscribers"][0]["name"] = "renamed_in_diagram"
    r = client.post("/api/print", json={"model": model}, headers=admin)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("text/plain")
    again = client.post("/api/validate", json={"text": r.text}, headers=admin).json()
    assert again["ok"] and again["model"] == model  # printed text reads back to the same model
    broken = client.post("/api/print", json={"model": {"drone": 3}}, headers=admin)
    assert broken.status_code == 422 and "not valid enough" in broken.json()["detail"]
    assert client.post("/api/print", json={"model": model}).status_code == 401


def test_import_collector_in_windows_1252_and_export_back(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    """A file of the original tool, saved by Eclipse in windows-1252, imports;
    the export for the original tool loads back to the same model."""
    text = "// Mission de température – 25 °C\n" + dumps(
        load_text(scenario1, "s.modd").model or {}, "modd"
    )
    text = (
        "DataCollector {\n"
        + text.replace("PubBroker(", "PubBroker broker(").replace("SubBroker(", "SubBroker base(")
        + "}\n"
    )
    r = client.post(
        "/api/projects/import",
        params={"name": "original", "format": "modd"},
        headers={**admin, "Content-Type": "text/plain"},
        content=text.encode("cp1252"),
    )
    assert r.status_code == 201, r.text
    pid = r.json()["id"]
    out = client.get(f"/api/projects/{pid}/export", params={"format": "collector"}, headers=admin)
    assert out.status_code == 200
    assert out.text.startswith("DataCollector {")
    back = load_text(out.text, "back.collector").model
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    assert back == model
    assert model["pubBroker"]["name"] == "broker"
