"""Where the platform is: the topics of its latitude, longitude and altitude.

A model declares them once (``drone.position``); without that, the MAVLink
autopilot's ``GLOBAL_POSITION_INT`` lat/lon/alt are used when a ``mavlink``
sensor maps them. ``modd dataset`` interpolates these to every sample.

>>> doc = {"drone": {"name": "d", "sensors": [{"name": "ap", "kind": "mavlink", "variables": [
...     {"name": "lat", "unit": "degree_north", "source": {"message": "GLOBAL_POSITION_INT",
...      "field": "lat"}},
...     {"name": "lon", "unit": "degree_east", "source": {"message": "GLOBAL_POSITION_INT",
...      "field": "lon"}}]}]}}
>>> p = platform_position(doc)
>>> p.latitude, p.longitude, p.altitude, p.declared
('d.ap.lat', 'd.ap.lon', None, False)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .query import topic_name
from .schema import definition

#: Seconds between two fixes across which a position is interpolated, when the model says none.
DEFAULT_MAX_GAP_S = float(definition("PlatformPosition")["properties"]["maxGapS"]["default"])
#: The autopilot's fused position (MAVLink common.xml): degE7, degE7, mm above MSL.
_MAVLINK_FIELDS = {"lat": "latitude", "lon": "longitude", "alt": "altitude"}
_MAVLINK_MESSAGE = "GLOBAL_POSITION_INT"


@dataclass(frozen=True)
class PlatformPosition:
    latitude: str
    longitude: str
    altitude: str | None
    max_gap_s: float
    declared: bool  # False: the MAVLink default


def platform_position(model: dict[str, Any]) -> PlatformPosition | None:
    """The model's position topics, or None when it has none."""
    drone = model["drone"]
    declared = drone.get("position")
    if declared is not None:
        return PlatformPosition(
            declared["latitude"],
            declared["longitude"],
            declared.get("altitude"),
            float(declared.get("maxGapS", DEFAULT_MAX_GAP_S)),
            True,
        )
    found: dict[str, str] = {}
    for sensor in drone["sensors"]:
        if sensor.get("kind") != "mavlink":
            continue
        for var in sensor["variables"]:
            src = var.get("source", {})
            role = _MAVLINK_FIELDS.get(src.get("field", ""))
            if src.get("message") == _MAVLINK_MESSAGE and role and role not in found:
                found[role] = topic_name(drone["name"], sensor["name"], var["name"])
    if "latitude" not in found or "longitude" not in found:
        return None
    return PlatformPosition(
        found["latitude"], found["longitude"], found.get("altitude"), DEFAULT_MAX_GAP_S, False
    )
