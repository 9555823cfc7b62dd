"""The 3D scene: each drone's track, from the subscriptions of its deployed
model that deliver a position (latitude/longitude[/altitude]), coloured by a
chosen subscribed value, with its attitude (roll/pitch/yaw) as a frame.

:class:`Track` is the pure part (what to draw from delivered values);
:class:`SceneServer` draws it with viser, which serves its own web client on
its own loopback port; browsers reach it only through the backend's
``/scene/`` proxy, behind the session (sceneproxy.py).

>>> roles = position_roles({"subscribers": [
...     {"name": "la", "topic": "d.gps.latitude"}, {"name": "lo", "topic": "d.gps.lon"}]})
>>> roles
{'la': 'lat', 'lo': 'lon'}
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any

from modd_contracts.delivered import load_delivered
from modd_contracts.keys import match_sub_key
from modd_contracts.types_gen import DeliveredValue

#: Variable names (last part of a topic) read as a position or an attitude.
ROLE_NAMES: dict[str, tuple[str, ...]] = {
    "lat": ("latitude", "lat"),
    "lon": ("longitude", "lon", "lng"),
    "alt": ("altitude", "alt"),
    "roll": ("roll",),
    "pitch": ("pitch",),
    "yaw": ("yaw", "heading"),
}
EARTH_RADIUS_M = 6_371_000.0
MAX_POINTS = 20_000


def position_roles(model: dict[str, Any]) -> dict[str, str]:
    """Subscriber name -> scene role, for subscribers whose topic is a
    position or attitude variable."""
    out: dict[str, str] = {}
    for sub in model.get("subscribers", []):
        variable = str(sub.get("topic", "")).rsplit(".", 1)[-1].lower()
        for role, names in ROLE_NAMES.items():
            if variable in names:
                out[str(sub["name"])] = role
    return out


def _colour(t: float) -> tuple[int, int, int]:
    """Blue (low) to red (high) through green."""
    t = min(1.0, max(0.0, t))
    if t < 0.5:
        return (0, int(510 * t), int(255 * (1 - 2 * t)))
    return (int(510 * (t - 0.5)), int(255 * (2 - 2 * t)), 0)


@dataclass
class Track:
    """One drone's track in local metres (east, north, up) from its first fix."""

    roles: dict[str, str]
    colour_by: str | None = None
    origin: tuple[float, float] | None = None
    points: list[tuple[float, float, float]] = field(default_factory=list)
    values: list[float | None] = field(default_factory=list)
    attitude: dict[str, float] = field(default_factory=dict)
    _fix: dict[str, float] = field(default_factory=dict)
    _last_value: float | None = None

    def ingest(self, subscriber: str, delivered: DeliveredValue) -> bool:
        """Take one delivered value; True when the drawing changed. A backfilled one
        (historical: an older window delivered late) is left out: the scene shows the
        drone as it is now, and its track's head and pose are the newest live values."""
        if delivered.get("backfilled") is True:
            return False
        value = delivered.get("value")
        if isinstance(value, list | tuple):  # AVERAGE travels as (mean, count) elsewhere
            value = value[0] if value else None
        if not isinstance(value, int | float) or isinstance(value, bool):
            return False
        if subscriber == self.colour_by:
            self._last_value = float(value)
        role = self.roles.get(subscriber)
        if role in ("roll", "pitch", "yaw"):
            self.attitude[role] = float(value)
            return True
        if role not in ("lat", "lon", "alt"):
            return False
        self._fix[role] = float(value)
        if role == "alt" or "lat" not in self._fix or "lon" not in self._fix:
            return False
        self._add_point(self._fix.pop("lat"), self._fix.pop("lon"), self._fix.get("alt", 0.0))
        return True

    def _add_point(self, lat: float, lon: float, alt: float) -> None:
        if self.origin is None:
            self.origin = (lat, lon)
        lat0, lon0 = self.origin
        east = math.radians(lon - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
        north = math.radians(lat - lat0) * EARTH_RADIUS_M
        self.points.append((east, north, alt))
        self.values.append(self._last_value)
        del self.points[:-MAX_POINTS], self.values[:-MAX_POINTS]

    def colours(self) -> list[tuple[int, int, int]]:
        known = [v for v in self.values if v is not None]
        if not known:
            return [(255, 255, 255)] * len(self.points)
        lo, hi = min(known), max(known)
        span = hi - lo or 1.0
        return [(200, 200, 200) if v is None else _colour((v - lo) / span) for v in self.values]

    def quaternion(self) -> tuple[float, float, float, float]:
        """wxyz from roll, pitch, yaw (radians, ZYX order)."""
        r, p, y = (self.attitude.get(k, 0.0) / 2 for k in ("roll", "pitch", "yaw"))
        cr, sr, cp, sp, cy, sy = (
            math.cos(r),
            math.sin(r),
            math.cos(p),
            math.sin(p),
            math.cos(y),
            math.sin(y),
        )
        return (
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        )


class SceneServer:
    """A viser server drawing the tracks; thread-safe ``draw``. It listens
    on a loopback address only (``host`` anything else is refused) and
    answers only requests carrying :attr:`secret`: the backend's proxy is the
    way in."""

    def __init__(self, host: str, port: int) -> None:
        import ipaddress

        import viser  # imported here: only a backend with a scene pays for it

        from .scenegate import gated_viser, new_secret

        if not ipaddress.ip_address(host).is_loopback:
            raise ValueError(f"the 3D scene listens on loopback only, not {host!r}")
        #: What the proxy sends; without it viser's port answers 403 (scenegate.py).
        self.secret = new_secret()
        with gated_viser(self.secret):
            self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self._user_controls()
        self.host = host
        self.port = self.server.get_port()
        self._lock = threading.Lock()

    def _user_controls(self) -> None:
        """What the panel shows users: a legend. viser shows its developer
        controls (Save Canvas, Dev Settings, share) while a scene has no GUI
        of its own; with one they stay behind its settings button."""
        gui = self.server.gui
        gui.configure_theme(show_logo=False, show_share_button=False)
        gui.add_markdown(
            "**Drone tracks**: each point a position, coloured by the "
            "chosen value; the axes show the attitude. Drag to orbit, "
            "scroll to zoom."
        )

    def draw(self, drone: str, track: Track) -> None:
        import numpy as np

        with self._lock:
            if track.points:
                self.server.scene.add_point_cloud(
                    f"/{drone}/track",
                    np.array(track.points, dtype=np.float32),
                    np.array(track.colours(), dtype=np.uint8),
                    point_size=1.0,
                    precision="float32",
                )
                self.server.scene.add_frame(
                    f"/{drone}/attitude",
                    axes_length=5.0,
                    axes_radius=0.3,
                    wxyz=track.quaternion(),
                    position=track.points[-1],
                )

    def stop(self) -> None:
        self.server.stop()


class SceneService:
    """Feeds the scene from zenoh: every delivered value of every drone
    (``modd/*/sub/*``) goes to that drone's :class:`Track`, whose roles come
    from the model last deployed to it (``models_of(drone)``)."""

    def __init__(self, server: SceneServer, model_of: Any) -> None:
        self.server = server
        self._model_of = model_of  # drone -> deployed model dict or None
        self.tracks: dict[str, Track] = {}
        self._colour: dict[str, str] = {}
        self._lock = threading.Lock()

    def track(self, drone: str) -> Track:
        with self._lock:
            found = self.tracks.get(drone)
            if found is None:
                model = self._model_of(drone) or {}
                found = Track(position_roles(model), self._colour.get(drone))
                self.tracks[drone] = found
            return found

    def on_value(self, key: str, payload: bytes) -> None:
        """zenoh callback for ``modd/<drone>/sub/<subscriber>``."""
        found = match_sub_key(key)
        if found is None:
            return
        delivered = load_delivered(payload)
        if delivered is not None:
            track = self.track(found[0])
            with self._lock:
                changed = track.ingest(found[1], delivered)
            if changed:
                self.server.draw(found[0], track)

    def colour_by(self, drone: str, subscriber: str | None) -> None:
        with self._lock:
            if subscriber is None:
                self._colour.pop(drone, None)
            else:
                self._colour[drone] = subscriber
        self.track(drone).colour_by = subscriber

    def forget(self, drone: str) -> None:
        """A new deployment: the roles are read again on the next value."""
        with self._lock:
            self.tracks.pop(drone, None)
