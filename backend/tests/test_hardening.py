"""Sessions, roles and resources under attack (docs/security.md, "HTTP and
WebSocket" and "Sessions"): each test reproduces a finding of the security
review and checks the answer the backend gives now."""

from __future__ import annotations

import io
import json
import statistics
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app
from modd_backend.errors import ApiError
from modd_backend.guards import HeavyLimiter
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Origin

from .conftest import ADMIN_PASSWORD, Headers, login
from .served import serve


def _settings(tmp_path: Path, **kw: Any) -> Settings:
    base: dict[str, Any] = {
        "data_dir": tmp_path / "data",
        "initial_admin_password": ADMIN_PASSWORD,
        "zenoh_enabled": False,
    }
    base.update(kw)
    return Settings(**base)


# --- live WebSockets on a served backend (zenoh session with no peers) -------


@pytest.fixture
def live_base(tmp_path: Path) -> Iterator[str]:
    settings = _settings(
        tmp_path,
        zenoh_enabled=True,
        zenoh_connect=(),
        ws_subscriptions_per_socket=100,
        ws_subscriptions_per_user=150,
    )
    with serve(settings) as base:
        yield base


def _api(base: str, method: str, path: str, token: str | None = None, **kw: Any) -> httpx.Response:
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    return httpx.request(method, base + path, headers=headers, timeout=30, **kw)


def _token(base: str, user: str, password: str) -> str:
    r = _api(base, "POST", "/api/auth/login", json={"username": user, "password": password})
    assert r.status_code == 200, r.text
    return str(r.json()["token"])


def _user(base: str, admin: str, name: str, *roles: str) -> tuple[int, str]:
    r = _api(
        base,
        "POST",
        "/api/users",
        admin,
        json={"username": name, "password": f"pw-{name}-12345", "roles": list(roles)},
    )
    assert r.status_code == 201, r.text
    return int(r.json()["id"]), _token(base, name, f"pw-{name}-12345")


def _stream(base: str, token: str) -> ClientConnection:
    ws = connect(base.replace("http", "ws") + "/api/drones/usv/stream", open_timeout=10)
    ws.send(json.dumps({"op": "auth", "token": token}))
    assert json.loads(ws.recv(timeout=10))["type"] == "authenticated"
    return ws


def _closed_after(ws: ClientConnection, timeout_s: float = 3.0) -> tuple[float, int | None]:
    t0 = time.monotonic()
    try:
        while time.monotonic() - t0 < timeout_s:
            ws.recv(timeout=timeout_s)
    except ConnectionClosed as exc:
        return time.monotonic() - t0, exc.rcvd.code if exc.rcvd else None
    except TimeoutError:
        pass
    return float("inf"), None


@pytest.mark.parametrize("action", ["logout", "password", "admin_reset", "roles", "delete"])
def test_websocket_closed_within_1s_of_session_change(live_base: str, action: str) -> None:
    base = live_base
    admin = _token(base, "admin", ADMIN_PASSWORD)
    uid, tok = _user(base, admin, "sam", "scientist")
    other = _token(base, "sam", "pw-sam-12345")  # the session that acts (own password)
    ws = _stream(base, tok)
    ws.send(json.dumps({"op": "subscribe", "subscriber": "sub_1"}))
    t0 = time.monotonic()
    if action == "logout":
        assert _api(base, "POST", "/api/auth/logout", tok).status_code == 204
    elif action == "password":
        r = _api(
            base,
            "PUT",
            "/api/auth/password",
            other,
            json={"old_password": "pw-sam-12345", "new_password": "new-pw-123456"},
        )
        assert r.status_code == 204
        assert _api(base, "GET", "/api/auth/me", tok).status_code == 401  # others revoked
        assert _api(base, "GET", "/api/auth/me", other).status_code == 200  # this one kept
    elif action == "admin_reset":
        r = _api(base, "PATCH", f"/api/users/{uid}", admin, json={"password": "reset-pw-1234"})
        assert r.status_code == 200
    elif action == "roles":
        r = _api(base, "PATCH", f"/api/users/{uid}", admin, json={"roles": []})
        assert r.status_code == 200
    else:
        assert _api(base, "DELETE", f"/api/users/{uid}", admin).status_code == 204
    acted = time.monotonic() - t0
    took, code = _closed_after(ws)
    assert code in (4401, 4403), (action, code)
    assert took + acted < 1.0 + acted and took < 1.0, f"{action}: closed after {took:.2f} s"


def test_subscription_cap_and_health_under_20000_ops(live_base: str) -> None:
    """20,000 subscribe ops on one socket: refused past the cap (100 per
    socket, 150 per user here) while /api/health keeps answering at once."""
    base = live_base
    admin = _token(base, "admin", ADMIN_PASSWORD)
    _uid, tok = _user(base, admin, "flood", "scientist")
    ws = _stream(base, tok)
    done = threading.Event()

    def flood() -> None:
        for i in range(20_000):
            ws.send(json.dumps({"op": "subscribe", "subscriber": f"s_{i}"}))
        done.set()

    sender = threading.Thread(target=flood)
    sender.start()
    latencies: list[float] = []
    with httpx.Client(timeout=10) as c:
        while not done.is_set() or len(latencies) < 50:
            t = time.perf_counter()
            assert c.get(base + "/api/health").status_code == 200
            latencies.append(time.perf_counter() - t)
            time.sleep(0.01)
    sender.join()
    ws.send(json.dumps({"op": "ping", "id": "p"}))
    pong = None
    deadline = time.monotonic() + 20
    while pong is None and time.monotonic() < deadline:
        msg = json.loads(ws.recv(timeout=20))
        if msg.get("type") == "pong":
            pong = msg
    assert pong is not None and len(pong["subscribers"]) == 100
    second = _stream(base, tok)
    replies: list[dict[str, Any]] = []
    for i in range(80):
        second.send(json.dumps({"op": "subscribe", "subscriber": f"t_{i}", "id": i}))
    while len(replies) < 80:
        msg = json.loads(second.recv(timeout=20))
        if "id" in msg:
            replies.append(msg)
    assert sum(m["type"] == "subscribed" for m in replies) == 50  # 150 per user in all
    assert all(m.get("code") == "cap" for m in replies if m["type"] == "error")
    ws.close()
    second.close()
    # generous here (a shared, loaded test machine); tests/bench/bench_health.py prints p99
    assert max(latencies) < 2.0, f"health stalled: max {max(latencies):.3f} s"


def test_websocket_refuses_token_in_url_and_foreign_origin(live_base: str) -> None:
    base = live_base
    tok = _token(base, "admin", ADMIN_PASSWORD)
    url = base.replace("http", "ws") + "/api/drones/usv/stream"
    for extra, origin in ((f"?token={tok}", None), ("", Origin("http://evil.example"))):
        with (
            pytest.raises(Exception, match="403|440"),
            connect(url + extra, open_timeout=10, origin=origin) as ws,
        ):
            ws.recv(timeout=5)
    # a cookie session from the workbench's own origin works
    r = httpx.post(
        base + "/api/auth/login",
        timeout=30,
        json={"username": "admin", "password": ADMIN_PASSWORD, "session": "cookie"},
    )
    cookie = r.cookies["modd_session"]
    with connect(
        url,
        open_timeout=10,
        origin=Origin(base),
        additional_headers={"Cookie": f"modd_session={cookie}"},
    ) as ws:
        ws.send(json.dumps({"op": "ping", "id": 1}))
        assert json.loads(ws.recv(timeout=10))["type"] == "pong"
    # ... but not from another origin (refused at the handshake)
    with (
        pytest.raises(Exception, match="403|4403"),
        connect(
            url,
            open_timeout=10,
            origin=Origin("http://evil.example"),
            additional_headers={"Cookie": f"modd_session={cookie}"},
        ) as ws,
    ):
        ws.recv(timeout=5)


def test_no_token_in_any_log(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    with serve(_settings(tmp_path, zenoh_enabled=True, zenoh_connect=())) as base:
        tok = _token(base, "admin", ADMIN_PASSWORD)
        assert _api(base, "GET", f"/api/projects?token={tok}", tok).status_code == 200
        url = base.replace("http", "ws") + f"/api/drones/usv/stream?token={tok}"
        with pytest.raises(Exception, match="403|4400"), connect(url, open_timeout=10) as ws:
            ws.recv(timeout=5)
        with _stream(base, tok) as ws:
            ws.send(json.dumps({"op": "ping"}))
            ws.recv(timeout=5)
    out, err = capfd.readouterr()
    logged = out + err
    assert "/api/projects?" in logged  # the line is there, its query is not
    assert tok not in logged
    for f in (tmp_path / "data").iterdir():
        assert f.stat().st_mode & 0o077 == 0, f"{f} is readable by others"


# --- HTTP, on the test client ------------------------------------------------


def test_login_throttled_per_account_and_address(tmp_path: Path) -> None:
    with TestClient(
        create_app(
            _settings(tmp_path, login_limit_account=5, login_limit_address=8), out=io.StringIO()
        )
    ) as c:
        for _ in range(5):
            r = c.post("/api/auth/login", json={"username": "admin", "password": "wrong"})
            assert r.status_code == 401
        r = c.post("/api/auth/login", json={"username": "admin", "password": ADMIN_PASSWORD})
        assert r.status_code == 429 and int(r.headers["Retry-After"]) >= 1
        for i in range(3):  # other names, same address
            c.post("/api/auth/login", json={"username": f"ghost{i}", "password": "x"})
        r = c.post("/api/auth/login", json={"username": "nobody", "password": "x"})
        assert r.status_code == 429 and "Retry-After" in r.headers


def test_unknown_user_answers_as_slowly_as_a_wrong_password(tmp_path: Path) -> None:
    with TestClient(
        create_app(
            _settings(tmp_path, login_limit_account=10**6, login_limit_address=10**6),
            out=io.StringIO(),
        )
    ) as c:

        def timed(user: str) -> float:
            t = time.perf_counter()
            assert (
                c.post("/api/auth/login", json={"username": user, "password": "wrong"}).status_code
                == 401
            )
            return time.perf_counter() - t

        known, unknown = [], []
        for i in range(12):
            known.append(timed("admin"))
            unknown.append(timed(f"ghost{i}"))
        k, u = statistics.median(known), statistics.median(unknown)
        # was 1.7 ms against 49 ms (x29); noise on a loaded machine stays well within x2
        assert 0.5 < u / k < 2.0, f"known {k * 1e3:.1f} ms, unknown {u * 1e3:.1f} ms"


@pytest.fixture
def small(tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(
        create_app(_settings(tmp_path, max_body_bytes=200_000), out=io.StringIO())
    ) as c:
        yield c


def test_oversized_and_overdeep_bodies_store_nothing(small: TestClient, scenario1: str) -> None:
    c = small
    h = login(c, "admin", ADMIN_PASSWORD)
    pid = c.post(
        "/api/projects", headers=h, json={"name": "p", "model": {"text": scenario1}}
    ).json()["id"]
    model = c.get(f"/api/projects/{pid}/model", headers=h).json()["model"]
    big = dict(model, subscribers=model["subscribers"] * 2000)
    r = c.put(f"/api/projects/{pid}/model", headers=h, json={"base_revision": 1, "model": big})
    assert r.status_code == 413 and "exceeds" in r.json()["detail"]

    def chunks() -> Iterator[bytes]:  # no Content-Length: counted as it arrives
        yield b'{"base_revision": 1, "model": {"x": "'
        for _ in range(50):
            yield b"a" * 10_000
        yield b'"}}'

    r = c.put(
        f"/api/projects/{pid}/model",
        content=chunks(),
        headers={**h, "Content-Type": "application/json"},
    )
    assert r.status_code == 413
    r = c.post("/api/projects/import?name=big", headers=h, content=b"x" * 300_000)
    assert r.status_code == 413
    deep: Any = 1
    for _ in range(300):
        deep = {"n": deep}
    r = c.put(
        f"/api/projects/{pid}/model",
        headers=h,
        json={"base_revision": 1, "model": dict(model, layout={"deep": deep})},
    )
    assert r.status_code == 422 and "nested" in r.json()["detail"]
    versions = c.get(f"/api/projects/{pid}/versions", headers=h).json()
    assert [v["revision"] for v in versions] == [1]
    assert [p["name"] for p in c.get("/api/projects", headers=h).json()] == ["p"]
    assert c.get(f"/api/projects/{pid}/model", headers=h).status_code == 200


def test_security_headers_on_every_answer(client: TestClient, admin: Headers) -> None:
    for path, h in (
        ("/api/health", {}),
        ("/api/projects", admin),
        ("/api/nothing", {}),
        ("/api/projects", {}),
    ):
        r = client.get(path, headers=h)
        csp = r.headers["content-security-policy"]
        script = next(d for d in csp.split(";") if d.strip().startswith("script-src"))
        assert "unsafe-inline" not in script and "frame-ancestors 'none'" in csp, path
        assert r.headers["x-content-type-options"] == "nosniff"
        assert r.headers["referrer-policy"] == "no-referrer"
        assert r.headers["x-frame-options"] == "DENY"


def test_map_tiles_only_from_configured_origins(tmp_path: Path) -> None:
    """No foreign image by default; a configured tile origin is allowed for images
    only (not scripts, frames or connections); a malformed one is refused."""

    def img_src(settings: Settings) -> tuple[str, str]:
        with TestClient(create_app(settings, out=io.StringIO())) as c:
            csp = c.get("/api/health").headers["content-security-policy"]
        return next(d for d in csp.split(";") if d.strip().startswith("img-src")), csp

    default, _ = img_src(_settings(tmp_path / "a"))
    assert default.split() == ["img-src", "'self'", "data:", "blob:"]
    tiles = "http://127.0.0.1:8123"
    images, csp = img_src(_settings(tmp_path / "b", tile_origins=(tiles,)))
    assert images.split() == ["img-src", "'self'", "data:", "blob:", tiles]
    assert csp.count(tiles) == 1
    for bad in (
        "http://127.0.0.1:8123/{z}/{x}/{y}.png",
        "javascript:alert(1)",
        "https://a b",
        "http://x; script-src *",
    ):
        with pytest.raises(ValueError, match="tile origin"):
            _settings(tmp_path / "c", tile_origins=(bad,))


def test_host_allow_list(tmp_path: Path) -> None:
    app = create_app(_settings(tmp_path, allowed_hosts=("modd.ship.lan",)), out=io.StringIO())
    with TestClient(app) as c:
        assert c.get("/api/health", headers={"Host": "evil.example"}).status_code == 400
        assert c.get("/api/health", headers={"Host": "evil.example:8000"}).status_code == 400
        for ok in ("127.0.0.1:8000", "localhost", "[::1]:8000", "modd.ship.lan:8000"):
            assert c.get("/api/health", headers={"Host": ok}).status_code == 200, ok


def test_last_admin_cannot_be_demoted_or_deleted(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers]
) -> None:
    me = client.get("/api/auth/me", headers=admin).json()
    r = client.patch(f"/api/users/{me['id']}", headers=admin, json={"roles": ["designer"]})
    assert r.status_code == 409 and "last admin" in r.json()["detail"]
    other = user_factory("root2", "admin")
    r = client.patch(f"/api/users/{me['id']}", headers=admin, json={"roles": ["designer"]})
    assert r.status_code == 200  # another admin is left
    r = client.delete(f"/api/users/{me['id']}", headers=other)
    assert r.status_code == 204
    root2 = client.get("/api/auth/me", headers=other).json()
    assert (
        client.patch(f"/api/users/{root2['id']}", headers=other, json={"roles": []}).status_code
        == 409
    )
    assert client.get("/api/users", headers=other).status_code == 200


def test_cookie_session_needs_csrf_header_on_unsafe_methods(client: TestClient) -> None:
    r = client.post(
        "/api/auth/login",
        json={"username": "admin", "password": ADMIN_PASSWORD, "session": "cookie"},
    )
    assert r.status_code == 200 and r.json()["token"] is None
    set_cookie = r.headers["set-cookie"].lower()
    assert "httponly" in set_cookie and "samesite=strict" in set_cookie
    csrf = r.json()["csrf"]
    assert client.get("/api/projects").status_code == 200  # cookie alone reads
    assert client.get("/api/auth/me").json()["csrf"] == csrf
    body = {"name": "p"}
    assert client.post("/api/projects", json=body).status_code == 403
    assert (
        client.post("/api/projects", json=body, headers={"X-CSRF-Token": "0" * 32}).status_code
        == 403
    )
    assert (
        client.post("/api/projects", json=body, headers={"X-CSRF-Token": csrf}).status_code == 201
    )
    assert client.post("/api/auth/logout", headers={"X-CSRF-Token": csrf}).status_code == 204
    assert client.get("/api/projects").status_code == 401


def test_heavy_limiter_refuses_at_once() -> None:
    lim = HeavyLimiter(per_user=1, total=2)
    with lim.slot(1):
        with pytest.raises(ApiError) as exc, lim.slot(1):
            pass
        assert exc.value.status == 429 and exc.value.headers == {"Retry-After": "1"}
        with lim.slot(2), pytest.raises(ApiError) as exc, lim.slot(3):
            pass
        assert exc.value.status == 503
    assert lim.in_flight == 0


def test_scene_colour_needs_a_role(
    client: TestClient, user_factory: Callable[..., Headers]
) -> None:
    nobody = user_factory("nobody")
    r = client.put("/api/scene/usv/colour", headers=nobody, json={"subscriber": None})
    assert r.status_code == 403


def test_api_docs_work_offline(client: TestClient) -> None:
    """/docs names no foreign origin: Swagger UI's files come from the backend."""
    page = client.get("/docs")
    assert page.status_code == 200
    assert "http" not in page.text.replace("http-equiv", "")  # no CDN, no absolute URL
    assert "/docs-assets/swagger-ui-bundle.js" in page.text
    csp = page.headers["content-security-policy"]
    assert "cdn" not in csp and "https:" not in csp
    for asset in ("swagger-ui-bundle.js", "swagger-ui.css"):
        r = client.get(f"/docs-assets/{asset}")
        assert r.status_code == 200 and len(r.content) > 10_000, asset
