"""A project's drones (routers/fleet.py) without a base station: the listing
of a campaign's drones from its mission model, the refusals (roles, unknown
drones, the one-drone deploy of a campaign). Deploys and subscriptions
against real drones: tests/twodrones/test_campaign_fleet.py."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from fastapi.testclient import TestClient
from modd_model import load_model
from modd_model.campaign import expand

from .conftest import Headers

EXAMPLES = Path(__file__).resolve().parents[2] / "metamodel" / "examples"


def _import(client: TestClient, headers: Headers, name: str, text: str) -> int:
    r = client.post(
        "/api/projects/import",
        params={"name": name, "format": "modd"},
        headers={**headers, "Content-Type": "text/plain"},
        content=text.encode(),
    )
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


def test_a_campaign_lists_its_drones_with_their_own_endpoints(
    client: TestClient, admin: Headers
) -> None:
    path = EXAMPLES / "campaign.modd"
    pid = _import(client, admin, "lake", path.read_text())
    fleet = client.get(f"/api/projects/{pid}/drones", headers=admin).json()
    expanded = expand(load_model(path))  # the oracle: the metamodel's own expansion
    assert fleet["campaign"] == "lake"
    assert [d["name"] for d in fleet["drones"]] == list(expanded) == ["usv1", "usv2", "usv3"]
    for d in fleet["drones"]:
        assert d["pub_broker"] == expanded[d["name"]]["pubBroker"]
        assert d["sub_broker"] == expanded[d["name"]]["subBroker"]
        assert d["deployment"] is None and d["status"] is None
    assert fleet["drones"][1]["description"] == "South boat"
    assert fleet["channels"] == {"ch1": ["usv1", "usv2"]}
    assert [d["channel"] for d in fleet["drones"]] == ["ch1", "ch1", None]


def test_a_one_drone_project_is_a_fleet_of_one(client: TestClient, admin: Headers) -> None:
    pid = _import(client, admin, "demo", (EXAMPLES / "demo.modd").read_text())
    fleet = client.get(f"/api/projects/{pid}/drones", headers=admin).json()
    assert fleet["campaign"] is None and fleet["channels"] == {}
    assert [d["name"] for d in fleet["drones"]] == ["usv"]
    assert fleet["drones"][0]["description"] == "Survey boat"


def test_refusals(client: TestClient, admin: Headers, user_factory: Callable[..., Headers]) -> None:
    pid = _import(client, admin, "lake", (EXAMPLES / "campaign.modd").read_text())
    operator, scientist = user_factory("op", "operator"), user_factory("sci", "scientist")
    one = client.post(f"/api/projects/{pid}/deployments", headers=operator, json={})
    assert one.status_code == 409
    assert "campaign of 3 drones" in one.json()["detail"] and "fleet/deployments" in one.text
    unknown = client.post(
        f"/api/projects/{pid}/fleet/deployments", headers=operator, json={"drones": ["nope"]}
    )
    assert unknown.status_code == 404 and "no drone nope" in unknown.json()["detail"]
    assert "usv1, usv2, usv3" in unknown.json()["detail"]
    denied = client.post(f"/api/projects/{pid}/fleet/deployments", headers=scientist, json={})
    assert denied.status_code == 403
    body = {"variable": "ctd.water_temperature", "period_s": "2", "aggregation": "AVERAGE"}
    sub = client.post(f"/api/projects/{pid}/fleet/subscriptions", headers=operator, json=body)
    assert sub.status_code == 403
    bad = client.post(
        f"/api/projects/{pid}/fleet/subscriptions",
        headers=scientist,
        json={
            **body,
            "variable": "usv.ctd.water_temperature",
        },  # a drone's topic, not sensor.variable
    )
    assert bad.status_code == 422
    assert client.get("/api/projects/999/drones", headers=admin).status_code == 404
    for path, who in (("deployments", operator), ("subscriptions", scientist)):
        none = client.post(
            f"/api/projects/{pid}/fleet/{path}", headers=who, json={**body, "drones": []}
        )
        assert none.status_code == 422, none.text  # an empty list is no fleet ("all" is no list)


def test_the_live_plan_says_a_shared_channel_is_over_its_rate(
    client: TestClient, admin: Headers
) -> None:
    text = (EXAMPLES / "campaign.modd").read_text()
    fits = client.post("/api/plan", headers=admin, json={"text": text}).json()
    assert fits["ok"] and not any(d["pointer"].startswith("/campaign") for d in fits["diagnostics"])
    over = text.replace("rate = 200000;", "rate = 10;")
    plan = client.post("/api/plan", headers=admin, json={"text": over}).json()
    (d,) = [d for d in plan["diagnostics"] if d["pointer"] == "/campaign/channels/0"]
    assert "over its rate of 10 B/s" in d["message"] and "usv1, usv2" in d["message"]
    assert d["severity"] == "warning"  # pinned on the channel, as a radio's refusal is
