"""Delivered values that survive a break in the mesh (docs/fleet.md, "A partition"):
zenoh's own recovery (``zenoh.ext`` advanced publishers and subscribers). A SubBroker
puts each subscriber's values through an advanced publisher that numbers them and keeps
the last ``CACHE_SAMPLES`` (10 minutes of a 4 Hz subscription); it tells its last
number every ``HEARTBEAT_S`` when it changed. A reader's advanced subscriber notices a
number it did not get (after a partition longer than zenoh's lease, a dropped put, a
router restarted) and asks that publisher's cache for it: each value comes once, in
order per publisher, and nothing is sent twice to a reader that had it.

The keys of this machinery are under ``<key>/@adv/...``, a verbatim chunk no ``**``
matches: the access control names them (:func:`modd.zenoh_auth.acl`, rule ``adv_*``).

A sample without a number (a plain publisher's, an older SubBroker's) passes an
advanced subscriber only if its timestamp is later than the last one it passed from
the same clock; a router stamps its clients' puts, so two plain publishers through one
router can lose a sample to reordering (docs/fleet.md, "A partition"). Every value a
SubBroker of this version puts is numbered.

>>> CACHE_SAMPLES >= 600 * 4
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import zenoh
import zenoh.ext as zx

#: Values kept per subscriber key for readers that missed them (~0.5 kB each).
CACHE_SAMPLES = 2400
#: Seconds between two tellings of a publisher's last number (only when it changed).
HEARTBEAT_S = 1.0


def values_publisher(
    session: zenoh.Session,
    key: str,
    encoding: zenoh.Encoding,
    congestion_control: zenoh.CongestionControl,
) -> Any:
    """An advanced publisher of one subscriber's values (``put``, ``undeclare``)."""
    return zx.declare_advanced_publisher(
        session,
        key,
        encoding=encoding,
        congestion_control=congestion_control,
        cache=zx.CacheConfig(max_samples=CACHE_SAMPLES),
        sample_miss_detection=zx.MissDetectionConfig(
            heartbeat=None, sporadic_heartbeat=HEARTBEAT_S
        ),
    )


def values_subscriber(
    session: zenoh.Session, key: str, callback: Callable[[zenoh.Sample], Any]
) -> Any:
    """An advanced subscriber of delivered values (``undeclare``): what it missed of a
    publisher it asks for again."""
    return zx.declare_advanced_subscriber(
        session, key, callback, recovery=zx.RecoveryConfig(periodic_queries=None, heartbeat=True)
    )
