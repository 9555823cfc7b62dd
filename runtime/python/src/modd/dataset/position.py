"""The platform's track and the position at any sample's time.

Each coordinate (latitude, longitude, altitude) is its own topic with its own
fixes, so each is interpolated on its own times: no pairing of fixes by time
is needed. Between two fixes the coordinate is linear in time; a sample
before the first fix, after the last, or in a gap longer than ``max_gap_ns``
gets NaN (written as the fill value): a position is never invented.

Fixes are cleaned first, and every change is reported: fixes out of time
order are sorted, repeated times keep the first, NaN/Inf fixes are dropped,
and so is a GPS glitch, a fix further from the last kept one than
``max_speed_ms`` allows (plus SLACK_M of noise).

>>> fix_t = np.array([0, 10, 20], dtype=np.int64) * 10**9
>>> coordinate_at(np.array([5, 15, 25]) * 10**9, fix_t, np.array([0.0, 1.0, 3.0]), 15 * 10**9)
array([0.5, 2. , nan])
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Metres per degree of latitude (the simulator's and a spherical Earth's).
METERS_PER_DEG = 111_320.0
#: A jump this short is never a glitch, whatever the time between fixes: a GNSS fix's
#: noise, and the step of a position sent as float32 (~0.5 m at mid latitudes).
SLACK_M = 5.0


def covered(times: np.ndarray, fix_t: np.ndarray, max_gap_ns: int) -> np.ndarray:
    """Which ``times`` the fixes cover: at a fix, or between two no more than
    ``max_gap_ns`` apart."""
    if len(fix_t) == 0:
        return np.zeros(times.shape, dtype=bool)
    nxt = np.searchsorted(fix_t, times, side="right")
    prev = nxt - 1
    exact = (prev >= 0) & (fix_t[np.clip(prev, 0, None)] == times)
    inside = (prev >= 0) & (nxt < len(fix_t))
    p, n = np.clip(prev, 0, len(fix_t) - 1), np.clip(nxt, 0, len(fix_t) - 1)
    short = inside & (fix_t[n] - fix_t[p] <= max_gap_ns)
    ok: np.ndarray = exact | short
    return ok


def coordinate_at(
    times: np.ndarray,
    fix_t: np.ndarray,
    fix_v: np.ndarray,
    max_gap_ns: int,
    ok: np.ndarray | None = None,
) -> np.ndarray:
    """``fix_v`` interpolated linearly to ``times`` (NaN outside the fixes or in a long
    gap); ``ok``: ``covered(times, fix_t, max_gap_ns)`` when known."""
    out = np.full(times.shape, np.nan)
    if len(fix_t) == 0:
        return out
    ok = covered(times, fix_t, max_gap_ns) if ok is None else ok
    out[ok] = np.interp(times[ok], fix_t, fix_v)
    return out


@dataclass
class Coordinate:
    """One coordinate's cleaned fixes (times in ns, values) and what cleaning did."""

    name: str
    t: np.ndarray
    v: np.ndarray
    notes: list[str] = field(default_factory=list)


def _glitches(
    t: np.ndarray, v: np.ndarray, metres_per_unit: float, max_speed_ms: float
) -> np.ndarray:
    """Mask of the fixes to keep: each is compared with the last kept one."""
    keep = np.ones(len(t), dtype=bool)
    jumps = np.abs(np.diff(v)) * metres_per_unit > max_speed_ms * np.diff(t) / 1e9 + SLACK_M
    if not jumps.any():
        return keep  # the usual track: no fix to compare one by one
    last = 0
    t, v = t.tolist(), v.tolist()
    for i in range(1, len(t)):
        dt = (t[i] - t[last]) / 1e9
        if abs(v[i] - v[last]) * metres_per_unit > max_speed_ms * dt + SLACK_M:
            keep[i] = False
        else:
            last = i
    return keep


def clean(
    name: str, t: np.ndarray, v: np.ndarray, metres_per_unit: float, max_speed_ms: float
) -> Coordinate:
    """Sorted, de-duplicated, finite, glitch-free fixes of one coordinate."""
    notes: list[str] = []
    v = v.astype(np.float64)
    if len(t) > 1 and np.any(np.diff(t) < 0):
        notes.append(f"{name}: fixes out of time order; sorted")
    order = np.argsort(t, kind="stable")
    t, v = t[order], v[order]
    finite = np.isfinite(v)
    if not finite.all():
        notes.append(f"{name}: {int((~finite).sum())} NaN/Inf fixes dropped")
        t, v = t[finite], v[finite]
    if len(t) > 1:
        first = np.concatenate([[True], np.diff(t) > 0])
        if not first.all():
            notes.append(f"{name}: {int((~first).sum())} fixes repeat a time; the first kept")
            t, v = t[first], v[first]
    keep = _glitches(t, v, metres_per_unit, max_speed_ms)
    if not keep.all():
        at = t[~keep][0] / 1e9
        notes.append(
            f"{name}: {int((~keep).sum())} fixes jump faster than {max_speed_ms:g} m/s "
            f"(GPS glitch; the first at t={at:.3f} s) and were dropped"
        )
        t, v = t[keep], v[keep]
    return Coordinate(name, t, v, notes)


@dataclass
class Track:
    """The platform's cleaned coordinates; altitude may be absent."""

    latitude: Coordinate
    longitude: Coordinate
    altitude: Coordinate | None
    max_gap_ns: int
    #: The longitude's fixes unwrapped across the antimeridian (computed once).
    unwrapped_lon: np.ndarray = field(init=False, repr=False)

    #: Latitude and longitude have the same fix times (one receiver's sentences): the
    #: samples they cover are found once.
    paired: bool = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.unwrapped_lon = np.unwrap(self.longitude.v, period=360.0)
        self.paired = np.array_equal(self.latitude.t, self.longitude.t)

    def at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(lat, lon, alt) at ``times`` (ns); NaN where unknown."""
        gap = self.max_gap_ns
        ok = covered(times, self.latitude.t, gap) if self.paired else None
        lat = coordinate_at(times, self.latitude.t, self.latitude.v, gap, ok)
        # across the antimeridian: interpolate the unwrapped longitude, then wrap
        lon = coordinate_at(times, self.longitude.t, self.unwrapped_lon, gap, ok)
        lon = (lon + 180.0) % 360.0 - 180.0
        alt = (
            coordinate_at(times, self.altitude.t, self.altitude.v, self.max_gap_ns)
            if self.altitude is not None
            else np.full(times.shape, np.nan)
        )
        return lat, lon, alt

    @property
    def notes(self) -> list[str]:
        coords = [self.latitude, self.longitude] + ([self.altitude] if self.altitude else [])
        return [n for c in coords for n in c.notes]


def build_track(
    fixes: dict[str, tuple[np.ndarray, np.ndarray]],
    max_gap_s: float,
    max_speed_ms: float,
    max_climb_ms: float,
) -> Track:
    """The track from raw fixes by role (``latitude``, ``longitude``, ``altitude``)."""
    lat_t, lat_v = fixes["latitude"]
    mid_lat = float(np.nanmedian(lat_v)) if len(lat_v) else 0.0
    lon_scale = METERS_PER_DEG * max(np.cos(np.radians(mid_lat)), 1e-6)
    lat = clean("latitude", lat_t, lat_v, METERS_PER_DEG, max_speed_ms)
    lon = clean("longitude", *fixes["longitude"], lon_scale, max_speed_ms)
    alt = clean("altitude", *fixes["altitude"], 1.0, max_climb_ms) if "altitude" in fixes else None
    return Track(lat, lon, alt, int(max_gap_s * 1e9))
