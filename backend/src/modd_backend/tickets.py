"""Viewer tickets: a single-use, short-lived stand-in for a session, for
viewers that can carry a credential only in the URL they open (Foxglove and
Lichtblick's "Foxglove WebSocket" connection).

The workbench hands out ``ws://HOST/foxglove/live?ticket=T``; opening it
spends ``T`` and the socket then lives on the session ``T`` stood for (it
closes when that session ends or its roles change). Only a hash of the ticket
is kept, and the access log cuts query strings (cli.RedactQuery), so a ticket
is never written anywhere.

A ticket is bound to its kind (``live`` or ``replay``: a live ticket does
not open the replay) and to the user it was issued to; a user has at most
``per_user`` outstanding (their own oldest forgotten first), so one user
asking for 10,001 cannot push everyone else's tickets out.

>>> t = ViewerTickets(ttl_s=60)
>>> ticket = t.issue("session-token", "live", 7, now=0)
>>> t.redeem(ticket, "live", now=1), t.redeem(ticket, "live", now=2)
('session-token', None)
>>> t.redeem(t.issue("session-token", "live", 7, now=0), "replay", now=1) is None
True
"""

from __future__ import annotations

import hashlib
import secrets
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass

#: Seconds a ticket may wait to be opened (time to paste it into a viewer).
TICKET_TTL_S = 300.0
#: Outstanding tickets of one user at most.
TICKETS_PER_USER = 32


def _key(ticket: str) -> str:
    return hashlib.sha256(ticket.encode()).hexdigest()


@dataclass(frozen=True)
class _Ticket:
    token: str
    kind: str
    user: int
    expires: float


class ViewerTickets:
    """At most ``per_user`` outstanding per user and ``max_tickets`` in all
    (the oldest forgotten first)."""

    def __init__(
        self,
        ttl_s: float = TICKET_TTL_S,
        max_tickets: int = 10_000,
        per_user: int = TICKETS_PER_USER,
    ) -> None:
        self.ttl_s = ttl_s
        self.max_tickets = max_tickets
        self.per_user = per_user
        self._open: OrderedDict[str, _Ticket] = OrderedDict()
        self._of_user: dict[int, OrderedDict[str, None]] = {}
        self._lock = threading.Lock()

    def issue(self, token: str, kind: str, user: int, now: float | None = None) -> str:
        now = time.monotonic() if now is None else now
        ticket = secrets.token_urlsafe(24)
        key = _key(ticket)
        with self._lock:
            self._open[key] = _Ticket(token, kind, user, now + self.ttl_s)
            mine = self._of_user.setdefault(user, OrderedDict())
            mine[key] = None
            while len(mine) > self.per_user:
                self._drop(next(iter(mine)))
            while len(self._open) > self.max_tickets:
                self._drop(next(iter(self._open)))
        return ticket

    def _drop(self, key: str) -> _Ticket | None:
        found = self._open.pop(key, None)
        if found is not None:
            mine = self._of_user.get(found.user)
            if mine is not None:
                mine.pop(key, None)
                if not mine:
                    del self._of_user[found.user]
        return found

    def redeem(self, ticket: str, kind: str, now: float | None = None) -> str | None:
        """The session token of ``ticket`` for a socket of ``kind``, once;
        None when unknown, spent, late or of another kind (a ticket of
        another kind is spent all the same)."""
        now = time.monotonic() if now is None else now
        if not ticket or len(ticket) > 128:
            return None
        with self._lock:
            found = self._drop(_key(ticket))
        if found is None or found.expires < now or found.kind != kind:
            return None
        return found.token

    def outstanding(self, user: int) -> int:
        with self._lock:
            return len(self._of_user.get(user, ()))
