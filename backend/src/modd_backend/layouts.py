"""A Foxglove/Lichtblick layout per project, for the scientist: one tab per
topic holding a plot per subscriber of that topic, a map of the drone's
position (``/<drone>/position``, a ``foxglove.LocationFix`` the Foxglove
server derives from the latitude/longitude subscriptions) and a table of the
link status (``/<drone>/link``). Import it in Foxglove or Lichtblick
(Layouts > Import from file) against the backend's Foxglove server.

Panel ids and configs follow the layout files Foxglove and Lichtblick export
(``configById`` + a mosaic ``layout`` tree); deterministic for one model.

>>> lay = foxglove_layout({"drone": {"name": "usv"}, "subscribers": [
...     {"name": "s1", "topic": "usv.ctd.temp", "aggregation": "AVERAGE", "periodS": "1"}]})
>>> sorted(lay["configById"])
['Plot!s1', 'Tab!topics', 'Table!usv-link', 'map!usv-position']
"""

from __future__ import annotations

from typing import Any


def _tree(ids: list[str], direction: str = "column") -> Any:
    """A balanced mosaic tree over panel ids (a single id is a leaf)."""
    if len(ids) == 1:
        return ids[0]
    half = len(ids) // 2
    return {
        "direction": direction,
        "first": _tree(ids[:half], direction),
        "second": _tree(ids[half:], direction),
        "splitPercentage": round(100 * half / len(ids), 1),
    }


def _plot(drone: str, sub: dict[str, Any]) -> dict[str, Any]:
    name = str(sub["name"])
    label = f"{name}: {sub.get('aggregation', '')} every {sub.get('periodS', '?')} s"
    return {
        "title": label,
        "paths": [
            {
                "value": f"/{drone}/{name}.value",
                "enabled": True,
                "timestampMethod": "receiveTime",
                "label": label,
            }
        ],
        "showXAxisLabels": True,
        "showYAxisLabels": True,
        "showLegend": True,
        "legendDisplay": "floating",
        "isSynced": True,
        "xAxisVal": "timestamp",
        "followingViewWidth": 120,
    }


def foxglove_layout(model: dict[str, Any]) -> dict[str, Any]:
    drone = str(model["drone"]["name"])
    by_topic: dict[str, list[dict[str, Any]]] = {}
    for sub in model.get("subscribers", []):
        by_topic.setdefault(str(sub.get("topic", "")), []).append(sub)
    config: dict[str, Any] = {}
    tabs = []
    for topic in sorted(by_topic):
        ids = []
        for sub in sorted(by_topic[topic], key=lambda s: str(s["name"])):
            pid = f"Plot!{sub['name']}"
            config[pid] = _plot(drone, sub)
            ids.append(pid)
        tabs.append({"title": topic, "layout": _tree(ids)})
    config["Tab!topics"] = {"activeTabIdx": 0, "tabs": tabs}
    map_id, table_id = f"map!{drone}-position", f"Table!{drone}-link"
    config[map_id] = {
        "center": None,
        "disabledTopics": [],
        "followTopic": f"/{drone}/position",
        "layer": "map",
        "topicColors": {},
        "zoomLevel": 14,
    }
    config[table_id] = {"topicPath": f"/{drone}/link"}
    side = {"direction": "column", "first": map_id, "second": table_id, "splitPercentage": 60}
    return {
        "configById": config,
        "globalVariables": {"drone": drone},
        "userNodes": {},
        "playbackConfig": {"speed": 1},
        "layout": {
            "direction": "row",
            "first": "Tab!topics",
            "second": side,
            "splitPercentage": 65,
        },
    }
