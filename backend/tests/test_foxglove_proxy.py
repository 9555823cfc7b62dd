"""Foxglove through the backend's port (docs/security.md, "Foxglove"): a
ticket opens ``/foxglove/live`` once; a foreign Origin, no session, a spent
ticket or a user without a role are refused at the upgrade; a logout or a
role removal closes the socket within a second; the SDK's own loopback port
speaks TLS with a certificate nobody but the backend trusts."""

from __future__ import annotations

import ssl
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from modd.ports import free_port
from modd_backend import Settings
from websockets.exceptions import ConnectionClosed, InvalidMessage, InvalidStatus
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Origin, Subprotocol

from .conftest import ADMIN_PASSWORD
from .served import serve
from .test_scene_proxy import _bearer, _login, make_users

FOXGLOVE = [Subprotocol("foxglove.sdk.v1")]


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, int]]:
    port = free_port()
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("fg") / "data",
        initial_admin_password=ADMIN_PASSWORD,
        zenoh_connect=(f"tcp/127.0.0.1:{free_port()}",),
        foxglove_port=port,
        ws_recheck_s=0.2,
    )
    with serve(settings) as url:
        make_users(url)
        yield url, port


def _live_url(base: str, token: str) -> str:
    r = httpx.post(base + "/api/foxglove/links", headers=_bearer(token), timeout=30)
    assert r.status_code == 200, r.text
    url = r.json()["live"]
    assert url.startswith(f"ws://{base[7:]}/foxglove/live?ticket=")
    return str(url)


def _open(url: str, origin: str | None = None, **kw: Any) -> ClientConnection:
    return connect(
        url,
        subprotocols=FOXGLOVE,
        open_timeout=10,
        origin=None if origin is None else Origin(origin),
        **kw,
    )


def _refused(url: str, origin: str | None = None, **kw: Any) -> int:
    with pytest.raises(InvalidStatus) as refused:
        _open(url, origin, **kw).close()
    return refused.value.response.status_code


def test_a_ticket_opens_live_once(base: tuple[str, int]) -> None:
    url, _port = base
    live = _live_url(url, _login(url, "sci", "pw-sci-12345"))
    with _open(live, url) as ws:  # the workbench's own origin
        assert ws.subprotocol == "foxglove.sdk.v1"
        assert '"op":"serverInfo"' in str(ws.recv(timeout=10))
    assert _refused(live) == 403  # spent


def test_refused_at_the_upgrade(base: tuple[str, int]) -> None:
    url, _port = base
    sci = _login(url, "sci", "pw-sci-12345")
    assert _refused(_live_url(url, sci), "http://evil.example") == 403
    with _open(_live_url(url, sci), "null") as ws:  # a desktop viewer's page, with a ticket
        assert ws.recv(timeout=10)
    cookie_null = {"Cookie": f"modd_session={sci}"}
    assert _refused(f"ws://{url[7:]}/foxglove/live", "null", additional_headers=cookie_null) == 403
    assert _refused(f"ws://{url[7:]}/foxglove/live") == 403  # no session
    assert _refused(f"ws://{url[7:]}/foxglove/live?ticket=made-up") == 403
    cookie = {"Cookie": f"modd_session={sci}"}
    assert _refused(f"ws://{url[7:]}/foxglove/live", None, additional_headers=cookie) == 403
    nobody = _login(url, "nobody", "pw-nobody-12345")
    r = httpx.post(url + "/api/foxglove/links", headers=_bearer(nobody), timeout=30)
    assert r.status_code == 403
    assert (
        _refused(f"ws://{url[7:]}/foxglove/live", None, additional_headers=_bearer(nobody)) == 403
    )


def _closed_within(ws: Any, act: Any, code: int) -> float:
    assert ws.recv(timeout=10)
    t0 = time.monotonic()
    act()
    with pytest.raises(ConnectionClosed) as closed:
        while time.monotonic() - t0 < 5:
            ws.recv(timeout=5)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == code
    return time.monotonic() - t0


def test_logout_and_role_removal_close_within_a_second(base: tuple[str, int]) -> None:
    url, _port = base
    sci = _login(url, "sci", "pw-sci-12345")
    with _open(_live_url(url, sci)) as ws:
        took = _closed_within(
            ws, lambda: httpx.post(url + "/api/auth/logout", headers=_bearer(sci), timeout=30), 4401
        )
        assert took < 1.0, took
    admin = _login(url, "admin", ADMIN_PASSWORD)
    users = httpx.get(url + "/api/users", headers=_bearer(admin), timeout=30).json()
    uid = next(u["id"] for u in users if u["username"] == "sci")
    sci = _login(url, "sci", "pw-sci-12345")
    with _open(_live_url(url, sci)) as ws:
        took = _closed_within(
            ws,
            lambda: httpx.patch(
                f"{url}/api/users/{uid}", json={"roles": []}, headers=_bearer(admin), timeout=30
            ),
            4403,
        )
        assert took < 1.0, took


def test_the_sdk_port_speaks_tls_nobody_trusts(base: tuple[str, int]) -> None:
    _url, port = base
    with pytest.raises(InvalidMessage):  # plain ws: no HTTP answer
        _open(f"ws://127.0.0.1:{port}").close()
    with pytest.raises(ssl.SSLCertVerificationError):
        _open(f"wss://127.0.0.1:{port}").close()


def test_ticket_store_forgets_and_expires(tmp_path: Path) -> None:
    from modd_backend.tickets import ViewerTickets

    t = ViewerTickets(ttl_s=10, max_tickets=2)
    first = t.issue("a", "live", 1, now=0)
    second, third = t.issue("b", "live", 2, now=0), t.issue("c", "live", 3, now=0)
    assert t.redeem(first, "live", now=1) is None  # forgotten: the oldest past max_tickets
    assert t.redeem(second, "live", now=11) is None  # late
    assert t.redeem(third, "live", now=9) == "c" and t.redeem(third, "live", now=9) is None
    assert t.redeem("x" * 500, "live") is None


def test_sockets_per_user_are_capped(tmp_path: Path) -> None:
    settings = Settings(
        data_dir=tmp_path / "data",
        initial_admin_password=ADMIN_PASSWORD,
        zenoh_connect=(f"tcp/127.0.0.1:{free_port()}",),
        foxglove_port=free_port(),
        ws_sockets_per_user=5,
    )
    with serve(settings) as url:
        admin = _bearer(_login(url, "admin", ADMIN_PASSWORD))
        live = f"ws://{url[7:]}/foxglove/live"
        opened = [_open(live, additional_headers=admin) for _ in range(5)]
        try:
            for ws in opened:
                assert ws.recv(timeout=10)
            assert _refused(live, additional_headers=admin) == 403  # the 6th: 4429
            opened.pop().close()
            deadline = time.monotonic() + 10
            while True:  # the slot comes back once the proxy has seen the close
                try:
                    opened.append(_open(live, additional_headers=admin))
                    break
                except InvalidStatus:
                    assert time.monotonic() < deadline, "the slot never came back"
                    time.sleep(0.1)
        finally:
            for ws in opened:
                ws.close()
