"""A campaign: one mission model flown by several vehicles.

A model with a ``campaign`` is the mission model of its vehicles. Each vehicle
is a drone of its own, made by :func:`expand`: the mission model with the
vehicle's name in place of the mission drone's (in every topic), its sensors'
devices, link settings and broker endpoints where the vehicle gives them. A
model without a campaign expands to itself: one drone, as before.

The checks here (registered with the validator) locate each problem in the
campaign (``/campaign/vehicles/i/...``): names twice, a channel or a sensor
that does not exist, two vehicles on one broker endpoint; and each vehicle's
expanded model is validated, its own problems reported at the vehicle.

>>> from modd_model.campaign import drone_names
>>> drone_names({"drone": {"name": "usv"}})
['usv']
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from typing import Any

from .diagnostics import Diagnostic, pointer_join

#: The campaign's own part of a model; an expanded drone model has none.
CAMPAIGN = "campaign"


def vehicles(model: dict[str, Any]) -> list[dict[str, Any]]:
    """The campaign's vehicles; none for a one-drone model."""
    campaign = model.get(CAMPAIGN)
    if not isinstance(campaign, dict):
        return []
    found = campaign.get("vehicles")
    return [v for v in found if isinstance(v, dict)] if isinstance(found, list) else []


def drone_names(model: dict[str, Any]) -> list[str]:
    """The drones a model deploys to: its vehicles, or its one drone."""
    named = [str(v.get("name", "")) for v in vehicles(model)]
    return named or [str((model.get("drone") or {}).get("name", ""))]


def expand(model: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """One drone model per vehicle, by drone name (the model itself, without
    a layout, when it has no campaign)."""
    found = vehicles(model)
    if not found:
        return {drone_names(model)[0]: model}
    return {str(v["name"]): vehicle_model(model, v) for v in found}


def vehicle_model(model: dict[str, Any], vehicle: dict[str, Any]) -> dict[str, Any]:
    """The drone model of one vehicle of ``model``'s campaign."""
    doc = copy.deepcopy({k: v for k, v in model.items() if k not in (CAMPAIGN, "layout")})
    mission, name = str(doc["drone"]["name"]), str(vehicle["name"])
    doc["drone"]["name"] = name
    if "description" in vehicle:
        doc["drone"]["description"] = vehicle["description"]

    def rename(topic: str) -> str:
        head, dot, rest = topic.partition(".")
        return f"{name}.{rest}" if dot and head == mission else topic

    for pub in doc.get("publishers", []):
        pub["topics"] = [rename(t) for t in pub.get("topics", [])]
    for sub in doc.get("subscribers", []):
        sub["topic"] = rename(str(sub.get("topic", "")))
    position = doc["drone"].get("position")
    if isinstance(position, dict):
        for key in ("latitude", "longitude", "altitude"):
            if isinstance(position.get(key), str):
                position[key] = rename(position[key])
    _apply_devices(doc, vehicle.get("devices", []))
    _apply_brokers(doc, vehicle)
    if "link" in vehicle:
        doc["link"] = _merged_link(doc.get("link", {}), vehicle["link"])
    return doc


def _apply_devices(doc: dict[str, Any], devices: list[dict[str, Any]]) -> None:
    by_sensor = {str(d["sensor"]): str(d["path"]) for d in devices}
    for sensor in doc["drone"].get("sensors", []):
        path = by_sensor.get(str(sensor.get("name")))
        if path is not None and isinstance(sensor.get("device"), dict):
            sensor["device"]["path"] = path


def _apply_brokers(doc: dict[str, Any], vehicle: dict[str, Any]) -> None:
    for part, path_key in (("pubBroker", "logPath"), ("subBroker", "configPath")):
        given = vehicle.get(part)
        if not isinstance(given, dict):
            continue
        doc[part]["endpoint"] = copy.deepcopy(given["endpoint"])
        if "path" in given:
            doc[part][path_key] = given["path"]


def _merged_link(mission: dict[str, Any], own: dict[str, Any]) -> dict[str, Any]:
    link = {**copy.deepcopy(mission), **{k: v for k, v in own.items() if k != "radio"}}
    if "radio" in own:
        link["radio"] = {**mission.get("radio", {}), **own["radio"]}
    return link


def channel_members(model: dict[str, Any]) -> dict[str, list[str]]:
    """The vehicles on each shared channel, by channel name."""
    campaign = model.get(CAMPAIGN) or {}
    out: dict[str, list[str]] = {str(c["name"]): [] for c in campaign.get("channels", [])}
    for v in vehicles(model):
        if v.get("channel") in out:
            out[str(v["channel"])].append(str(v["name"]))
    return out


# -- validation ------------------------------------------------------------


def campaign_checks(model: dict[str, Any]) -> Iterator[Diagnostic]:
    """The campaign's own problems, each located in it."""
    campaign = model.get(CAMPAIGN)
    if not isinstance(campaign, dict):
        return
    channels = campaign.get("channels", [])
    yield from _twice([c["name"] for c in channels], "/campaign/channels", "channel")
    found = vehicles(model)
    yield from _twice([v["name"] for v in found], "/campaign/vehicles", "vehicle")
    names = {str(c["name"]) for c in channels}
    sensors = {str(s["name"]): s for s in model["drone"].get("sensors", [])}
    for i, v in enumerate(found):
        ptr = pointer_join("campaign", "vehicles", i)
        if "channel" in v and v["channel"] not in names:
            known = ", ".join(sorted(names)) or "none declared"
            yield Diagnostic(
                f"vehicle {v['name']!r}: no channel {v['channel']!r} in the campaign ({known})",
                ptr + "/channel",
            )
        yield from _device_checks(v, sensors, ptr)
    yield from _shared_endpoints(model, found)


def _twice(names: list[Any], ptr: str, what: str) -> Iterator[Diagnostic]:
    first: dict[str, int] = {}
    for i, n in enumerate(names):
        if n in first:
            yield Diagnostic(
                f"{what} {n!r} is declared twice (first at {ptr}/{first[n]})",
                ptr + pointer_join(i, "name"),
            )
        else:
            first[str(n)] = i


def _device_checks(
    vehicle: dict[str, Any], sensors: dict[str, dict[str, Any]], ptr: str
) -> Iterator[Diagnostic]:
    seen: set[str] = set()
    for j, d in enumerate(vehicle.get("devices", [])):
        at, sensor = ptr + pointer_join("devices", j, "sensor"), str(d["sensor"])
        if sensor in seen:
            yield Diagnostic(f"sensor {sensor!r}'s device is given twice", at)
        seen.add(sensor)
        if sensor not in sensors:
            yield Diagnostic(f"the mission model has no sensor {sensor!r}", at)
        elif not isinstance(sensors[sensor].get("device"), dict):
            yield Diagnostic(f"sensor {sensor!r} reads no device: nothing to replace", at)


def _shared_endpoints(model: dict[str, Any], found: list[dict[str, Any]]) -> Iterator[Diagnostic]:
    """Each vehicle carries its own PubBroker: two on one endpoint is a mistake.
    (One base station may serve several drones: SubBroker endpoints may be shared.)"""
    owner: dict[tuple[str, int], str] = {}
    for i, v in enumerate(found):
        ep = (v.get("pubBroker") or model.get("pubBroker") or {}).get("endpoint") or {}
        key = (str(ep.get("host")), int(ep.get("port", 0)))
        if key in owner:
            yield Diagnostic(
                f"vehicles {owner[key]!r} and {v['name']!r} have one PubBroker endpoint "
                f"{key[0]}:{key[1]}: give each vehicle its own (PubBroker in the vehicle)",
                pointer_join("campaign", "vehicles", i, "pubBroker"),
            )
        else:
            owner[key] = str(v["name"])


def vehicle_diagnostics(
    model: dict[str, Any], mission: list[Diagnostic], validate: Any
) -> Iterator[Diagnostic]:
    """Each vehicle's expanded model validated: its errors that the mission
    model does not have, located at the vehicle."""
    known = {d.message for d in mission}
    for i, v in enumerate(vehicles(model)):
        ptr = pointer_join("campaign", "vehicles", i)
        for d in validate(vehicle_model(model, v)):
            if d.severity != "error" or _as_mission(d.message, str(v["name"]), model) in known:
                continue
            where = ptr + ("/link" + d.pointer[5:] if d.pointer.startswith("/link") else "")
            yield Diagnostic(f"vehicle {v['name']!r}: {d.message}", where)


def _as_mission(message: str, name: str, model: dict[str, Any]) -> str:
    return message.replace(f"{name}.", f"{model['drone']['name']}.")
