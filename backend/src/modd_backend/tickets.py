"""Viewer tickets: a single-use, short-lived stand-in for a session, for
viewers that can carry a credential only in the URL they open (Foxglove and
Lichtblick's "Foxglove WebSocket" connection).

The workbench hands out ``ws://HOST/foxglove/live?ticket=T``; opening it
spends ``T`` and the socket then lives on the session ``T`` stood for (it
closes when that session ends or its roles change). Only a hash of the ticket
is kept, and the access log cuts query strings (cli.RedactQuery), so a ticket
is never written anywhere.

>>> t = ViewerTickets(ttl_s=60)
>>> ticket = t.issue("session-token", now=0)
>>> t.redeem(ticket, now=1), t.redeem(ticket, now=2)
('session-token', None)
"""

from __future__ import annotations

import hashlib
import secrets
import threading
import time
from collections import OrderedDict

#: Seconds a ticket may wait to be opened (time to paste it into a viewer).
TICKET_TTL_S = 300.0


def _key(ticket: str) -> str:
    return hashlib.sha256(ticket.encode()).hexdigest()


class ViewerTickets:
    """At most ``max_tickets`` outstanding (the oldest forgotten first)."""

    def __init__(self, ttl_s: float = TICKET_TTL_S, max_tickets: int = 10_000) -> None:
        self.ttl_s = ttl_s
        self.max_tickets = max_tickets
        self._open: OrderedDict[str, tuple[str, float]] = OrderedDict()
        self._lock = threading.Lock()

    def issue(self, token: str, now: float | None = None) -> str:
        now = time.monotonic() if now is None else now
        ticket = secrets.token_urlsafe(24)
        with self._lock:
            self._open[_key(ticket)] = (token, now + self.ttl_s)
            while len(self._open) > self.max_tickets:
                self._open.popitem(last=False)
        return ticket

    def redeem(self, ticket: str, now: float | None = None) -> str | None:
        """The session token of ``ticket``, once; None when unknown, spent or late."""
        now = time.monotonic() if now is None else now
        if not ticket or len(ticket) > 128:
            return None
        with self._lock:
            found = self._open.pop(_key(ticket), None)
        if found is None or found[1] < now:
            return None
        return found[0]
