"""The Foxglove/Lichtblick layout download (scientist's role): a plot per
subscriber grouped by topic, a map of the position, the link status table;
every panel of the mosaic tree has its config and every config is shown."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from typing import Any

from fastapi.testclient import TestClient
from modd_backend.layouts import foxglove_layout

from .conftest import Headers


def _leaves(tree: Any) -> Iterator[str]:
    if isinstance(tree, str):
        yield tree
    else:
        yield from _leaves(tree["first"])
        yield from _leaves(tree["second"])


def test_scientist_downloads_the_layout(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers], scenario1: str
) -> None:
    pid = client.post(
        "/api/projects", headers=admin, json={"name": "fox glove", "model": {"text": scenario1}}
    ).json()["id"]
    sci, designer = user_factory("fx_sci", "scientist"), user_factory("fx_des", "designer")
    assert client.get(f"/api/projects/{pid}/foxglove-layout", headers=designer).status_code == 403
    r = client.get(f"/api/projects/{pid}/foxglove-layout", headers=sci)
    assert r.status_code == 200 and r.headers["content-type"] == "application/json"
    assert (
        r.headers["content-disposition"]
        == 'attachment; filename="fox_glove-r1-foxglove-layout.json"'
    )
    layout = r.json()
    model = client.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    drone, subs = model["drone"]["name"], model["subscribers"]
    config = layout["configById"]
    # the mosaic: tabs beside the map over the table; every leaf is configured
    shown = set(_leaves(layout["layout"]))
    tabs = config["Tab!topics"]["tabs"]
    for tab in tabs:
        shown |= set(_leaves(tab["layout"]))
    assert shown == set(config)
    # one tab per topic, one plot per subscriber of that topic, on its channel
    assert sorted(t["title"] for t in tabs) == sorted({s["topic"] for s in subs})
    for tab in tabs:
        plots = [config[p] for p in _leaves(tab["layout"])]
        names = {s["name"] for s in subs if s["topic"] == tab["title"]}
        assert {p["paths"][0]["value"] for p in plots} == {f"/{drone}/{n}.value" for n in names}
    assert config[f"map!{drone}-position"]["followTopic"] == f"/{drone}/position"
    assert config[f"Table!{drone}-link"]["topicPath"] == f"/{drone}/link"
    assert client.get("/api/projects/999/foxglove-layout", headers=sci).status_code == 404


def test_layout_is_deterministic() -> None:
    model = {
        "drone": {"name": "d"},
        "subscribers": [
            {"name": n, "topic": t, "aggregation": "MIN", "periodS": "1"}
            for n, t in [("b", "d.x.y"), ("a", "d.x.y"), ("c", "d.x.z")]
        ],
    }
    one = json.dumps(foxglove_layout(model))
    assert one == json.dumps(foxglove_layout(model))
    tabs = foxglove_layout(model)["configById"]["Tab!topics"]["tabs"]
    assert tabs[0]["layout"]["first"] == "Plot!a"
