"""The live plan returns the planning engine's own output for the paper's
scenarios, and diagnostics instead of a plan for bad models."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient
from modd_model import load_model
from modd_plan import make_plan

from .conftest import Headers


def test_scenario1_plan_is_the_planners(
    client: TestClient,
    admin: Headers,
    scenarios_dir: Path,
    scenario1: str,
    expected: dict[str, Any],
) -> None:
    r = client.post("/api/plan", headers=admin, json={"text": scenario1})
    assert r.status_code == 200
    body = r.json()
    assert body["ok"] and body["diagnostics"] == []
    plan = body["plan"]
    exp = expected["scenario1"]
    assert plan["buffer_sizes"] == exp["buffer_sizes"]
    assert float(plan["hyperperiod_s"]) == exp["hyperperiod_s"]
    assert plan["messages_per_hyperperiod"] == exp["messages_per_hyperperiod"]
    assert plan == make_plan(load_model(scenarios_dir / "scenario1.modd")).to_json()
    for key in ("schedule", "delays", "predicted_link_bytes_per_s", "infeasible"):
        assert key in plan


def test_scenario2_with_the_milp(
    client: TestClient, admin: Headers, scenario2: str, expected: dict[str, Any]
) -> None:
    body = client.post("/api/plan?method=cvxpy", headers=admin, json={"text": scenario2}).json()
    sizes = set(body["plan"]["buffer_sizes"].values())
    assert sizes == {expected["scenario2"]["buffer_sizes_all_topics"]}


def test_bad_model_gives_diagnostics_not_a_plan(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    body = client.post(
        "/api/plan", headers=admin, json={"text": scenario1.replace("2.0, AVERAGE", "2.0, MODE")}
    ).json()
    assert body["ok"] is False and body["plan"] is None
    assert body["diagnostics"][0]["pointer"] == "/subscribers/0/aggregation"
    syntax = client.post("/api/plan", headers=admin, json={"text": "Drone {"}).json()
    assert syntax["plan"] is None and syntax["diagnostics"][0]["line"] == 1


def test_infeasibility_is_reported(client: TestClient, admin: Headers, scenario1: str) -> None:
    # 0.25 s and 10 s on one topic: no buffer size keeps both delays under 3 x PING.
    far = scenario1.replace(
        "Subscriptions {",
        'Subscriptions {\n    Subscriber slow("usv.accelerometer.accel_z", 10.0, MAX);',
    )
    body = client.post("/api/plan", headers=admin, json={"text": far}).json()
    assert body["ok"], body["diagnostics"]
    assert body["plan"]["violates_delay_cap"] is True
    infeasible = body["plan"]["infeasible"]
    assert infeasible and infeasible[0]["topic"] == "usv.accelerometer.accel_z"


def test_plan_of_a_stored_revision(client: TestClient, admin: Headers, scenario1: str) -> None:
    pid = client.post(
        "/api/projects", headers=admin, json={"name": "p", "model": {"text": scenario1}}
    ).json()["id"]
    body = client.get(f"/api/projects/{pid}/plan", headers=admin).json()
    assert body["plan"]["buffer_sizes"]["usv.accelerometer.accel_z"] == 6
    assert client.get("/api/plan").status_code == 405
    assert client.post("/api/plan", json={"text": scenario1}).status_code == 401


def test_bodies_that_are_not_a_model_input_get_fastapis_422(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    """The body is read in the planning worker, not by FastAPI on the event
    loop: the answers to bodies that are not a ModelInput keep FastAPI's
    422 form (``detail`` items with ``loc`` from ``body``)."""

    def post(**kw: Any) -> Any:
        return client.post("/api/plan", headers={**admin, **kw.pop("headers", {})}, **kw)

    r = post(content=b'{"text": ', headers={"content-type": "application/json"})
    assert r.status_code == 422
    assert r.json()["detail"][0]["type"] == "json_invalid"
    assert r.json()["detail"][0]["loc"][0] == "body"
    r = post(json={"text": scenario1, "model": {}})
    assert r.status_code == 422
    assert "exactly one" in r.json()["detail"][0]["msg"]
    r = post(json={"text": 3})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "text"]
    r = post(content=b"", headers={"content-type": "application/json"})
    assert r.status_code == 422 and r.json()["detail"][0]["type"] == "missing"
    r = post(content=scenario1.encode(), headers={"content-type": "text/plain"})
    assert r.status_code == 422
    r = post(json={"text": scenario1}, headers={"content-type": "application/vnd.x+json"})
    assert r.status_code == 200 and r.json()["ok"]
    spec = client.get("/openapi.json").json()
    body = spec["paths"]["/api/plan"]["post"]["requestBody"]
    assert body["content"]["application/json"]["schema"]["$ref"].endswith("/ModelInput")


def test_a_plan_refused_by_its_radio_carries_its_report(
    client: TestClient, admin: Headers, scenario1: str
) -> None:
    # at 2 %: at 1 % the link's control traffic leaves scenario 1 no plan that fits
    # (docs/planning.md, "Control traffic")
    link = (
        'Link { transport = serial; device = "/dev/ttyUSB0"; radio = lora; sf = 7; '
        "dutyCycle = 0.02; }\n"
    )
    body = client.post("/api/plan", headers=admin, json={"text": scenario1 + link}).json()
    assert body["ok"]
    radio = body["plan"]["radio"]
    assert radio["duty_share"] > 1 and radio["proposals"]
    warnings = [(d["pointer"], d["severity"]) for d in body["diagnostics"]]
    assert ("/link/radio", "warning") in warnings and ("/subscribers/4", "warning") in warnings
