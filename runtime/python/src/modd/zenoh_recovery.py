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

zenoh's subscriber asks once: when that ask gets no answer (right after a partition
heals, while the mesh's routes converge) it gives those numbers up and goes on. So a
reader here watches each publisher's numbers itself (:class:`_AskAgain`): a jump is
values given up, asked for again from that publisher's cache after ``ASK_AGAIN_S``, each
delivered once when it comes; so are the first values of a publisher first heard past
its number 0 well after the reader subscribed (zenoh's subscriber asks nothing of a
publisher it did not know).

A sample without a number (a plain publisher's, an older SubBroker's) passes an
advanced subscriber only if its timestamp is later than the last one it passed from
the same clock; a router stamps its clients' puts, so two plain publishers through one
router can lose a sample to reordering (docs/fleet.md, "A partition"). Every value a
SubBroker of this version puts is numbered.

>>> CACHE_SAMPLES >= 600 * 4
True
"""

from __future__ import annotations

import logging
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import zenoh
import zenoh.ext as zx

log = logging.getLogger("modd.zenoh_recovery")

#: Values kept per subscriber key for readers that missed them (~0.5 kB each).
CACHE_SAMPLES = 2400
#: Seconds between two tellings of a publisher's last number (only when it changed).
HEARTBEAT_S = 1.0
#: When values zenoh's recovery gave up on are asked for again (seconds after the jump).
ASK_AGAIN_S = (1.0, 2.0, 4.0, 8.0, 16.0)
#: Publishers a reader follows the numbers of (the least recently heard forgotten first).
MAX_SOURCES = 1024
#: A publisher first heard this long after the reader subscribed, at a number past 0, is
#: one whose first values the reader missed (it began while the reader was cut off: a
#: station that took a drone over while this reader's router was down); they are asked for.
NEW_SOURCE_AFTER_S = 5.0


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
    publisher it asks for again, and again when zenoh's one ask went unanswered."""
    again = _AskAgain(session, callback)
    sub = zx.declare_advanced_subscriber(
        session,
        key,
        again.on_sample,
        recovery=zx.RecoveryConfig(periodic_queries=None, heartbeat=True),
    )
    return _Subscription(sub, again)


class _Subscription:
    def __init__(self, sub: Any, again: _AskAgain) -> None:
        self._sub, self._again = sub, again

    def undeclare(self) -> None:
        self._again.close()
        self._sub.undeclare()


class _AskAgain:
    """Each publisher's numbers as the callback gets them: a jump (zenoh's subscriber gave
    those up) is asked for again from the publisher's cache, at most CACHE_SAMPLES of it,
    at ASK_AGAIN_S; a value asked for is delivered when it comes, once; any other number
    at or below the last one is a copy, dropped."""

    def __init__(self, session: zenoh.Session, callback: Callable[[zenoh.Sample], Any]) -> None:
        self._session, self._callback = session, callback
        self._lock = threading.Lock()
        self._last: OrderedDict[tuple[str, int], int] = OrderedDict()
        self._missing: dict[tuple[str, int], set[int]] = {}
        self._closed = threading.Event()
        self._since = time.monotonic()

    def on_sample(self, sample: zenoh.Sample) -> None:
        info = sample.source_info
        if info is None:
            self._callback(sample)
            return
        source = (str(info.source_id.zid), int(info.source_id.eid))
        sn = int(info.source_sn)
        with self._lock:
            last = self._last.get(source)
            missing = self._missing.get(source)
            if last is None or sn > last:
                if last is None and sn > 0 and time.monotonic() - self._since > NEW_SOURCE_AFTER_S:
                    last = -1  # its values from the first one were put while this reader heard
                if last is not None and sn > last + 1:
                    gap = set(range(max(last + 1, sn - CACHE_SAMPLES), sn))
                    if missing is None:
                        self._missing[source] = gap
                        self._start(source, str(sample.key_expr))
                    else:
                        missing.update(gap)
                self._last[source] = sn
                self._last.move_to_end(source)
                while len(self._last) > MAX_SOURCES:
                    gone, _ = self._last.popitem(last=False)
                    self._missing.pop(gone, None)
                fresh = True
            else:
                fresh = missing is not None and sn in missing
                if fresh:
                    missing.discard(sn)  # type: ignore[union-attr]
        if fresh:
            self._callback(sample)

    def _start(self, source: tuple[str, int], key: str) -> None:
        thread = threading.Thread(
            target=self._ask, args=(source, key), name="modd-ask-again", daemon=True
        )
        thread.start()

    def _ask(self, source: tuple[str, int], key: str) -> None:
        zid, eid = source
        for delay in ASK_AGAIN_S:
            if self._closed.wait(delay):
                return
            with self._lock:
                wanted = sorted(self._missing.get(source) or ())
            if not wanted:
                break
            selector = f"{key}/@adv/pub/{zid}/{eid}/**?_sn={wanted[0]}..{wanted[-1]}"
            try:
                replies = self._session.get(
                    selector,
                    consolidation=zenoh.ConsolidationMode.NONE,
                    accept_replies=zenoh.ReplyKeyExpr.ANY,
                    timeout=2.0,
                )
                for reply in replies:
                    if reply.ok is not None:
                        self.on_sample(reply.ok)
            except zenoh.ZError:  # the session is closing
                return
        with self._lock:
            left = self._missing.pop(source, set())
        if left:
            log.warning(
                "%d values of %s from publisher %s/%d could not be had again (its cache "
                "no longer holds them, or it is gone)",
                len(left),
                key,
                zid,
                eid,
            )

    def close(self) -> None:
        self._closed.set()
