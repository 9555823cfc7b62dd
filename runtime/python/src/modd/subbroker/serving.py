"""Which base station serves a drone heard by several (docs/fleet.md, "Serving station").

A PubBroker keeps one base station's link at a time (a newly authenticated one
replaces the previous: docs/protocol.md), so two stations that both connect would
take the drone from each other in turn. The stations that can serve a drone
elect one with zenoh liveliness tokens, through the router mesh:

- every candidate holds ``modd/<drone>/fleet/candidate/<station>``;
- the one whose link is up holds ``modd/<drone>/fleet/serving/<station>``;
- a candidate connects only while no other station serves, the first in name
  order at once, the next ones after ``grace_s`` per rank (the first may not hear
  the drone); one that sees another serve drops its link (two that came up at
  once after a partition: the first in name order stays).

A station that dies loses its tokens when its router sees its session close (at
once for a process that ends, within the zenoh lease for a silent one), and the
next candidate connects. :attr:`cut` is what the link's pump asks
(:class:`~.rehearsal.CutSwitch`'s interface): True while this station must not connect.

>>> e = Election("b", grace_s=2.0, settle_s=1.0); e.candidates = {"a", "b"}
>>> e.decide(now=0.0), e.decide(now=3.5)   # "a" ranks first: "b" waits its grace
(False, True)
>>> e.serving = {"a"}; e.decide(now=4.0)     # "a" serves now: "b" stands back
False
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from modd_contracts.keys import candidate_key, serving_key

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker.serving")

#: Seconds a candidate waits per rank before it tries the drone (the ones before it may
#: not hear it).
GRACE_S = 2.0
#: Seconds every candidate waits after the drone's station went (or at start) before it
#: tries: the liveliness tokens of the others reach it within this time.
SETTLE_S = 1.0


class Election:
    """One station's view of who serves one drone (no I/O: :class:`ServingSwitch` feeds it)."""

    def __init__(self, station: str, grace_s: float = GRACE_S, settle_s: float = SETTLE_S) -> None:
        self.station = station
        self.grace_s = grace_s
        self.settle_s = settle_s
        self.candidates: set[str] = {station}
        self.serving: set[str] = set()
        self.up = False  # this station's link is up
        self._vacant_since: float | None = None

    def decide(self, now: float) -> bool:
        """Whether this station may hold the drone's link now."""
        others = self.serving - {self.station}
        if others:
            self._vacant_since = None
            # after a partition heals two may serve: the first in name order stays
            return self.up and self.station < min(others)
        if self.up:
            return True
        if self._vacant_since is None:
            self._vacant_since = now
        rank = sorted(self.candidates | {self.station}).index(self.station)
        return now - self._vacant_since >= self.settle_s + rank * self.grace_s


class ServingSwitch:
    """The election of one drone's SubBroker on its zenoh session: tokens, liveliness
    subscribers, and :attr:`cut` for the link's pump."""

    #: what the status says of the link while another station serves (the schema's LinkState)
    state = "down"
    why = "another base station serves the drone"
    #: a datagram link listens while cut (dglink.py): the serving station uses what it hears
    overhears = True

    def __init__(
        self,
        session: zenoh.Session,
        drone: str,
        station: str,
        is_up: Callable[[], bool],
        on_change: Callable[[bool], None] = lambda serving: None,
    ) -> None:
        self.drone = drone
        self._is_up = is_up
        self._on_change = on_change
        self.election = Election(station)
        self._session = session
        self._lock = threading.Lock()
        self._serving_token: Any = None
        live = session.liveliness()
        self._candidate_token = live.declare_token(candidate_key(drone, station))
        candidates = candidate_key(drone, station).rsplit("/", 1)[0] + "/*"
        self._subs = [
            live.declare_subscriber(candidates, self._on_candidate, history=True),
            live.declare_subscriber(serving_key(drone, None), self._on_serving, history=True),
        ]

    def _name(self, key: object) -> str:
        return str(key).rsplit("/", 1)[1]

    def _on_candidate(self, sample: zenoh.Sample) -> None:
        self._update(self.election.candidates, sample)

    def _on_serving(self, sample: zenoh.Sample) -> None:
        self._update(self.election.serving, sample)

    def _update(self, names: set[str], sample: zenoh.Sample) -> None:
        import zenoh

        name = self._name(sample.key_expr)
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                names.add(name)
            else:
                names.discard(name)

    @property
    def cut(self) -> bool:
        """Asked by the link's pump before each connect and while the link runs."""
        up = self._is_up()
        self._sync(up)
        with self._lock:
            allowed = self.election.decide(time.monotonic())
        return not allowed

    def _sync(self, up: bool) -> None:
        """The link is up (this station serves: its token) or down (its token gone);
        ``on_change`` is told when that changes."""
        with self._lock:
            self.election.up = up
            changed = up != (self._serving_token is not None)
            if up and self._serving_token is None:
                key = serving_key(self.drone, self.election.station)
                self._serving_token = self._session.liveliness().declare_token(key)
                log.info("station %s serves %s", self.election.station, self.drone)
            elif not up and self._serving_token is not None:
                self._serving_token.undeclare()
                self._serving_token = None
        if changed:
            self._on_change(up)

    def another_serves(self) -> bool:
        """Whether another station holds the drone's link now."""
        with self._lock:
            return bool(self.election.serving - {self.election.station})

    def describe(self) -> dict[str, Any]:
        with self._lock:
            e = self.election
            return {
                "station": e.station,
                "serving": sorted(e.serving),
                "candidates": sorted(e.candidates),
            }

    def close(self) -> None:
        self._sync(False)
        for sub in self._subs:
            sub.undeclare()  # type: ignore[no-untyped-call]
        self._candidate_token.undeclare()  # type: ignore[no-untyped-call]
