"""``POST /api/plan?calibrate=DRONE/NAME.mcap``: the live plan calibrated by an
archive the backend holds (written by the official ``mcap`` writer), the same
as the planner calibrated by that file directly; nothing outside the archive
directory; an archive without the model's topics is a diagnostic."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_model import load_model
from modd_plan import make_plan
from modd_plan.calibration import Calibration
from modd_plan.cli import load_calibration

from .conftest import Headers
from .test_archives import TOPICS, archive_client

__all__ = ["archive_client"]  # the fixture, shared with test_archives


@pytest.fixture
def model(scenarios_dir: Path) -> dict[str, Any]:
    m = load_model(scenarios_dir / "scenario1.modd")
    for v in m["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01, validMin=-100, validMax=100)
    m["link"] = {"transport": "serial", "device": "/dev/null", "radio": {"kind": "lora"}}
    return m


def test_the_live_plan_is_calibrated_by_a_held_archive(
    archive_client: tuple[TestClient, Headers, Path], model: dict[str, Any]
) -> None:
    c, h, root = archive_client
    r = c.post(
        "/api/plan", headers=h, params={"calibrate": "usv/run-0000.mcap"}, json={"model": model}
    )
    assert r.status_code == 200, r.text
    plan = r.json()["plan"]
    radio = plan["radio"]
    assert radio["calibrated_from"] == "run-0000.mcap" and radio["figures"] == "estimate"
    # the archive holds accel_x and accel_z: accel_y's stream keeps its bound
    assert [k.split("/")[0] for k in radio["calibration"]["not_calibrated"]] == [
        "usv.accelerometer.accel_y"
    ]
    direct = load_calibration(str(root / "usv" / "run-0000.mcap"), list(TOPICS))
    assert plan == make_plan(model, calibration=direct).to_json()
    assert plan != make_plan(model, calibration=Calibration("run-0000.mcap", {})).to_json()


@pytest.mark.parametrize("where", ["usv/link.mcap", "usv/none.mcap", "usv/../x.mcap", "x"])
def test_only_archives_of_the_archive_directory(
    archive_client: tuple[TestClient, Headers, Path], model: dict[str, Any], where: str
) -> None:
    c, h, _ = archive_client
    r = c.post("/api/plan", headers=h, params={"calibrate": where}, json={"model": model})
    assert r.status_code in (404, 422), r.text


def test_an_archive_without_the_models_topics_is_a_diagnostic(
    archive_client: tuple[TestClient, Headers, Path], model: dict[str, Any]
) -> None:
    c, h, _ = archive_client
    model["drone"]["name"] = "boat"  # other topic names: boat.accelerometer.accel_x ...
    for s in model["subscribers"]:
        s["topic"] = s["topic"].replace("usv.", "boat.")
    for p in model["publishers"]:
        p["topics"] = [t.replace("usv.", "boat.") for t in p["topics"]]
    body = c.post(
        "/api/plan", headers=h, params={"calibrate": "usv/run-0000.mcap"}, json={"model": model}
    ).json()
    assert body["ok"] is False and body["plan"] is None
    d = body["diagnostics"][-1]
    assert d["pointer"] == "/link/radio"
    assert "cannot calibrate the plan" in d["message"] and "holds no sample" in d["message"]
