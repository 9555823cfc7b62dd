"""The SubBroker's status on ``modd/<drone>/status``: link state, RTT,
running config, bytes/s in and out, last DATA time, the PubBroker's own
counters (from its STATUS frames), the planner's prediction and whether the
SubBroker keeps up with the link (:mod:`.backpressure`: ``behind``,
``lag_s``, ...), as one JSON object every ``status_period_s``
(docs/subbroker.md, "Status").

Byte rates here are link frame bytes as the SubBroker reads and writes them;
``ip_bytes_in_per_s`` adds 52 bytes of IPv4+TCP headers per frame received,
the estimate to hold against the planner's ``drone_to_base`` (which counts
headers). tests/bench/bench_link.py measures the real thing with tshark.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .keys import status_key
from .linkhooks import LinkStats

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker.status")

#: IPv4 (20) + TCP with the timestamps option (32): what one segment costs on loopback.
HEADER_BYTES = 52


class Rates:
    """Per-second rates of the link counters between two snapshots."""

    def __init__(self) -> None:
        self._last: tuple[float, int, int, int] | None = None

    def update(self, stats: LinkStats) -> dict[str, float | None]:
        now = time.monotonic()
        current = (now, stats.bytes_in, stats.bytes_out, stats.frames_in)
        last, self._last = self._last, current
        if last is None or now <= last[0]:
            return {"bytes_in_per_s": None, "bytes_out_per_s": None, "ip_bytes_in_per_s": None}
        dt = now - last[0]
        bytes_in = (current[1] - last[1]) / dt
        frames_in = (current[3] - last[3]) / dt
        return {
            "bytes_in_per_s": round(bytes_in, 1),
            "bytes_out_per_s": round((current[2] - last[2]) / dt, 1),
            "ip_bytes_in_per_s": round(bytes_in + HEADER_BYTES * frames_in, 1),
        }


class StatusPublisher:
    """Puts ``snapshot()`` (plus byte rates) on the status key periodically."""

    def __init__(
        self,
        session: zenoh.Session,
        drone: str,
        period_s: float,
        snapshot: Callable[[], dict[str, Any]],
        stats: Callable[[], LinkStats],
    ) -> None:
        self._pub = session.declare_publisher(status_key(drone))
        self._period = period_s
        self._snapshot = snapshot
        self._stats = stats
        self._rates = Rates()
        self._stop = threading.Event()
        self._publishing = threading.Lock()  # the period's thread and an event's (a deploy)
        self._thread = threading.Thread(target=self._run, name="modd-status", daemon=True)
        self.last: dict[str, Any] = {}
        #: True while another base station serves the drone (serving.py): its status is
        #: the drone's, this station's would say "down" in between (docs/fleet.md).
        self.quiet: Callable[[], bool] = lambda: False

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._pub.undeclare()  # type: ignore[no-untyped-call]

    def publish_now(self) -> dict[str, Any]:
        with self._publishing:
            status = self._snapshot()
            stats = self._stats()
            status.update(self._rates.update(stats))
            status.update(stats.backpressure.as_dict())
            self.last = status
            if not self.quiet():
                self._pub.put(json.dumps(status, separators=(",", ":")))
            return status

    def _run(self) -> None:
        while not self._stop.wait(self._period):
            try:
                self.publish_now()
            except Exception:  # a status must never kill the SubBroker
                log.exception("status publication failed")
