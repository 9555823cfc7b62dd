"""Who may open a connection to the SubBroker's zenoh listener now: the per-source
bounds of the accept gate (docs/security.md, "Connections per source"). zenoh's
``transport/unicast`` settings bound the connections in their handshake for the whole
listener (``accept_pending``) but not per source, so one address churning connections
could hold every other viewer out; this table bounds each source's connections in
their handshake (``per_source_pending``) and the rate it may open new ones
(``per_source_rate``, a token bucket), in a table of at most ``max_sources`` entries.

>>> t = SourceTable(GateLimits(per_source_pending=1, per_source_rate=10), clock=lambda: 0.0)
>>> t.admit("127.0.0.9") is None, t.admit("127.0.0.9")
(True, 'per_source_pending: 1 connection of 127.0.0.9 being set up')
"""

from __future__ import annotations

import ipaddress
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Any

#: The first bytes the gate sends to a connection it turns away, before it closes it:
#: a zenoh client fails on them as on a close; MoDD's probe reads the reason after it.
REFUSAL_MARK = b"MODD-GATE "


@dataclass(frozen=True)
class GateLimits:
    """``[zenoh.gate]`` of the SubBroker's configuration (docs/subbroker.md)."""

    #: Put the gate in front of the zenoh listener (tcp/ and tls/ endpoints).
    enabled: bool = True
    #: Connections of one source in their handshake at once (younger than the
    #: listener's ``accept_timeout``); more are refused at once.
    per_source_pending: int = 32
    #: New connections per second one source may open (burst: twice as many).
    per_source_rate: float = 20.0
    #: Sources remembered at once (bounded memory); idle ones are forgotten first.
    max_sources: int = 4096

    def __post_init__(self) -> None:
        for name in ("per_source_pending", "per_source_rate", "max_sources"):
            if not getattr(self, name) > 0:
                raise ValueError(f"zenoh.gate.{name}: expected a number above 0")

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str) -> GateLimits:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(
                f"{where}: unknown key {unknown[0]!r}; known: {', '.join(sorted(known))}"
            )
        if "enabled" in data and not isinstance(data["enabled"], bool):
            raise ValueError(f"{where}.enabled: expected true or false")
        for key in known - {"enabled"}:
            value = data.get(key)
            if value is not None and (
                isinstance(value, bool) or not isinstance(value, int | float)
            ):
                raise ValueError(f"{where}.{key}: expected a number, got {value!r}")
        try:
            return cls(**data)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: {exc}") from exc


def source_of(address: str) -> str:
    """The key a connection is counted under: its IPv4 address, or its IPv6 /64
    (one host holds a whole /64)."""
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:
        return address
    if isinstance(ip, ipaddress.IPv6Address):
        if ip.ipv4_mapped is not None:
            return str(ip.ipv4_mapped)
        return str(ipaddress.ip_network(f"{ip}/64", strict=False))
    return str(ip)


@dataclass
class _Source:
    pending: int = 0  # connections accepted, not yet past the accept timeout, open
    open: int = 0  # connections open (pending or not)
    tokens: float = 0.0
    stamp: float = 0.0  # when ``tokens`` was last refilled
    refused: int = 0  # since the last log line about this source
    logged: float = float("-inf")  # when the last log line about this source was written


class SourceTable:
    """Admission per source; every call from one thread (the gate's loop)."""

    def __init__(self, limits: GateLimits, clock: Callable[[], float] = time.monotonic):
        self.limits, self.clock = limits, clock
        self.burst = 2 * limits.per_source_rate
        self._sources: dict[str, _Source] = {}

    def __len__(self) -> int:
        return len(self._sources)

    def admit(self, source: str) -> str | None:
        """None: admitted (counted open and pending); else why it is refused."""
        s = self._sources.get(source) or self._new(source)
        if s is None:
            return f"max_sources: {self.limits.max_sources} sources with connections open"
        now = self.clock()
        s.tokens = min(self.burst, s.tokens + (now - s.stamp) * self.limits.per_source_rate)
        s.stamp = now
        why = self._over(source, s)
        if why is not None:
            s.refused += 1
            return why
        s.tokens -= 1.0
        s.pending += 1
        s.open += 1
        return None

    def _over(self, source: str, s: _Source) -> str | None:
        limits = self.limits
        if s.pending >= limits.per_source_pending:
            n = s.pending
            return f"per_source_pending: {n} connection{'s'[: n != 1]} of {source} being set up"
        if s.tokens < 1.0:
            return f"per_source_rate: {source} opens more than {limits.per_source_rate:g} a second"
        return None

    def settled(self, source: str) -> None:
        """A connection of ``source`` is past its handshake time (still open)."""
        s = self._sources.get(source)
        if s is not None and s.pending > 0:
            s.pending -= 1

    def closed(self, source: str, was_pending: bool) -> None:
        s = self._sources.get(source)
        if s is None:
            return
        s.open = max(0, s.open - 1)
        if was_pending and s.pending > 0:
            s.pending -= 1

    def due_report(self, source: str, every_s: float) -> int:
        """Connections of ``source`` refused since its last log line, when a line is due
        (at most one per ``every_s``); else 0."""
        s = self._sources.get(source)
        now = self.clock()
        if s is None or s.refused == 0 or now - s.logged < every_s:
            return 0
        n, s.refused, s.logged = s.refused, 0, now
        return n

    def _new(self, source: str) -> _Source | None:
        if len(self._sources) >= self.limits.max_sources:
            self._forget_idle()
        if len(self._sources) >= self.limits.max_sources:
            return None
        s = _Source(tokens=self.burst, stamp=self.clock())
        self._sources[source] = s
        return s

    def _forget_idle(self) -> None:
        """Drops the sources with nothing open whose bucket is full again: what they
        could do next is what a new source may do."""
        now = self.clock()
        rate = self.limits.per_source_rate
        idle = [
            k
            for k, s in self._sources.items()
            if s.open == 0 and s.tokens + (now - s.stamp) * rate >= self.burst
        ]
        if not idle:  # none fully idle: the least recently seen with nothing open
            idle = [
                k
                for _, k in sorted((s.stamp, k) for k, s in self._sources.items() if s.open == 0)[
                    :1
                ]
            ]
        for k in idle:
            del self._sources[k]
