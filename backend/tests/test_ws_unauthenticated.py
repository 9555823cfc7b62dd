"""Unauthenticated stream sockets are closed fast and cheaply (issue 41,
docs/security.md): at most ``ws_unauthenticated_per_address`` wait for their
first-message auth at once per address, each for ``ws_auth_timeout_s``; the
ones beyond are refused before the accept (HTTP 403: no task, no timer), the
waiting ones closed with 4401 when their time is up, and the slots come back.
Against uvicorn on loopback, as the service runs."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator

import httpx2 as httpx
import pytest
from modd.ports import free_port
from modd_backend import Settings
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import ClientConnection, connect

from .conftest import ADMIN_PASSWORD
from .served import serve

WAITING, TIMEOUT_S = 8, 4.0


@pytest.fixture
def base(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("unauth") / "data",
        initial_admin_password=ADMIN_PASSWORD,
        zenoh_connect=(f"tcp/127.0.0.1:{free_port()}",),
        ws_unauthenticated_per_address=WAITING,
        ws_auth_timeout_s=TIMEOUT_S,
    )
    with serve(settings) as url:
        yield url


def _stream(base: str) -> ClientConnection:
    return connect(f"ws://{base[7:]}/api/drones/usv/stream", open_timeout=10)


def test_unauthenticated_sockets_are_capped_and_closed_in_time(base: str) -> None:
    opened_at = time.monotonic()
    waiting = [_stream(base) for _ in range(WAITING)]  # accepted, never authenticating
    refusals = 0
    # while every one of them still waits, the others are refused at the handshake
    while refusals < 100 and time.monotonic() < opened_at + TIMEOUT_S - 0.5:
        t0 = time.monotonic()
        with pytest.raises(InvalidStatus) as refused:
            _stream(base).close()
        assert refused.value.response.status_code == 403
        assert time.monotonic() - t0 < 2.0  # no wait for a refusal
        refusals += 1
    assert refusals > 0, "the machine took the whole auth time to open the sockets"
    assert httpx.get(base + "/api/health", timeout=5).status_code == 200
    for ws in waiting:  # each closed with 4401 once its time is up
        with pytest.raises(ConnectionClosed) as closed:
            ws.recv(timeout=TIMEOUT_S + 5)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 4401
    assert time.monotonic() - opened_at < TIMEOUT_S + 2.0
    token = httpx.post(
        base + "/api/auth/login",
        json={"username": "admin", "password": ADMIN_PASSWORD},
        timeout=30,
    ).json()["token"]
    deadline = time.monotonic() + 5
    while True:  # the slots come back: an authenticating socket is served
        try:
            ws = _stream(base)
            break
        except InvalidStatus:
            assert time.monotonic() < deadline, "the waiting slots never came back"
            time.sleep(0.1)
    with ws:
        ws.send(json.dumps({"op": "auth", "token": token}))
        assert json.loads(ws.recv(timeout=10))["type"] == "authenticated"
