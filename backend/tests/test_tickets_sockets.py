"""Tickets and sockets (issue 41): a ticket opens only its kind and is
spent by a try of another; one user's tickets are capped (asking 10,001
pushes out only their own); the Origin is compared with its scheme; an
absolute-form target's query is cut from the log; other accounts at one
address cannot fill its socket cap and lock the operator out."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest
from modd_backend.cli import RedactQuery
from modd_backend.routers.live import origin_allowed
from modd_backend.settings import Settings
from modd_backend.socketcaps import SocketCaps, SocketFull
from modd_backend.tickets import ViewerTickets
from starlette.websockets import WebSocket


def test_a_live_ticket_does_not_open_the_replay() -> None:
    t = ViewerTickets()
    live = t.issue("tok", "live", 1)
    assert t.redeem(live, "replay") is None
    assert t.redeem(live, "live") is None  # spent by the wrong try: no second chance
    replay = t.issue("tok", "replay", 1)
    assert t.redeem(replay, "replay") == "tok"


def test_one_user_asking_10001_tickets_evicts_only_their_own() -> None:
    t = ViewerTickets()
    others = [t.issue(f"tok{u}", "live", u) for u in range(2, 50)]
    for _ in range(10_001):
        t.issue("greedy", "live", 1)
    assert t.outstanding(1) == t.per_user
    assert [t.redeem(x, "live") for x in others] == [f"tok{u}" for u in range(2, 50)]


def _socket(origin: str, host: str, scheme: str = "ws") -> WebSocket:
    scope = {
        "type": "websocket",
        "scheme": scheme,
        "path": "/foxglove/live",
        "query_string": b"",
        "server": ("127.0.0.1", 8080),
        "headers": [(b"origin", origin.encode()), (b"host", host.encode())],
    }

    async def nothing() -> dict[str, str]:
        return {}

    return WebSocket(scope, nothing, nothing)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("origin", "scheme", "allowed"),
    [
        ("http://127.0.0.1:8080", "ws", True),
        ("https://127.0.0.1:8080", "wss", True),
        ("https://127.0.0.1:8080", "ws", False),
        ("ftp://127.0.0.1:8080", "ws", False),
        ("http://127.0.0.1:8080", "wss", False),
        ("127.0.0.1:8080", "ws", False),
    ],
)
def test_the_origin_is_compared_with_its_scheme(origin: str, scheme: str, allowed: bool) -> None:
    settings = Settings(data_dir=Path("/nonexistent"), zenoh_enabled=False)
    assert origin_allowed(_socket(origin, "127.0.0.1:8080", scheme), settings) is allowed


def test_an_absolute_form_target_is_redacted_in_the_access_log() -> None:
    args = ("127.0.0.1:5555", "ws://127.0.0.1:8080/foxglove/live?ticket=SECRET", "[accepted]")
    record = logging.LogRecord("uvicorn.error", 20, "", 0, '%s - "WebSocket %s" %s', args, None)
    RedactQuery().filter(record)
    assert "SECRET" not in record.getMessage()
    plain = logging.LogRecord("a", 20, "", 0, "%s %s", ("/api/x?ticket=S", "GET"), None)
    RedactQuery().filter(plain)
    assert "S" not in plain.getMessage().split("?")[1]


def test_other_accounts_at_one_address_cannot_lock_the_operator_out() -> None:
    caps = SocketCaps(per_user=64, per_address=512)
    held = []
    for user in range(2, 12):  # ten accounts, 64 sockets each, all from loopback
        for _ in range(64):
            try:
                slot = caps.slot(user, "127.0.0.1")
                slot.__enter__()
                held.append(slot)
            except SocketFull:
                break
    assert caps.addresses["loopback"] == 512  # the address's cap holds for them
    operator = [caps.slot(1, "127.0.0.9") for _ in range(caps.reserved)]
    for slot in operator:
        slot.__enter__()  # the operator's own sockets open
    with pytest.raises(SocketFull):
        caps.slot(1, "127.0.0.1").__enter__()  # beyond the reserve: the full address's cap
    for slot in operator + held:
        slot.__exit__(None, None, None)
    assert not caps.users and not caps.addresses
