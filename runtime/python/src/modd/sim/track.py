"""Where the simulated drone is and how it moves: a lawnmower survey over a
stretch of water (back-and-forth legs), with gentle waves on the attitude, and
the warm, fresh plume the water sensors see. Every simulated value — the
autopilot's MAVLink messages and the scientific sensors — comes from here, so
they agree with one another (a track coloured by water temperature shows the
plume where the autopilot says the drone was).

``t`` is seconds since the track's start (``modd-sim --start-time``).

Example::

    p = survey_pose(12.5)       # p.lat, p.lon (degrees), p.yaw (radians, 0 = north)
    roll, pitch = waves(12.5)   # radians
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ORIGIN_LAT, ORIGIN_LON = 47.70, -3.35  # a sheltered bay
LEG_M, SPACING_M, LEGS, SPEED_MS = 400.0, 40.0, 8, 2.0
METERS_PER_DEG_LAT = 111_320.0


@dataclass(frozen=True)
class Pose:
    lat: float
    lon: float
    yaw: float  # radians, 0 = north, pi/2 = east
    x: float  # metres east of the origin
    y: float  # metres north of the origin

    @property
    def velocity(self) -> tuple[float, float]:
        """(north, east) in m/s: the drone moves along its heading at SPEED_MS."""
        return SPEED_MS * math.cos(self.yaw), SPEED_MS * math.sin(self.yaw)


def survey_pose(t: float) -> Pose:
    """Where the drone is t seconds into a lawnmower survey (it loops)."""
    leg_time = LEG_M / SPEED_MS
    turn_time = SPACING_M / SPEED_MS
    period = LEGS * (leg_time + turn_time)
    t %= period
    leg, rest = divmod(t, leg_time + turn_time)
    leg = int(leg)
    north = leg % 2 == 0
    if rest < leg_time:
        y = rest * SPEED_MS if north else LEG_M - rest * SPEED_MS
        x, yaw = leg * SPACING_M, 0.0 if north else math.pi
    else:
        y = LEG_M if north else 0.0
        x, yaw = leg * SPACING_M + (rest - leg_time) * SPEED_MS, math.pi / 2
    lat = ORIGIN_LAT + y / METERS_PER_DEG_LAT
    lon = ORIGIN_LON + x / (METERS_PER_DEG_LAT * math.cos(math.radians(ORIGIN_LAT)))
    return Pose(lat, lon, yaw, x, y)


def altitude(t: float) -> float:
    """Metres above sea level: the swell."""
    return 0.2 * math.sin(0.5 * t)


def waves(t: float) -> tuple[float, float]:
    """(roll, pitch) in radians."""
    return (0.05 * math.sin(2 * math.pi * 0.3 * t), 0.03 * math.sin(2 * math.pi * 0.25 * t + 1.0))


def battery(t: float) -> tuple[float, float, int]:
    """(volts, amperes, percent remaining) of a 4S pack draining over three hours."""
    left = max(0.0, 1.0 - t / 10_800.0)
    return 14.0 + 2.8 * left, 8.5 + 0.5 * math.sin(0.1 * t), round(100 * left)


def plume(p: Pose) -> float:
    """0..1: how deep in the warm, fresh plume the drone is."""
    return math.exp(-((p.x - 250) ** 2 + (p.y - 300) ** 2) / (2 * 90.0**2))
