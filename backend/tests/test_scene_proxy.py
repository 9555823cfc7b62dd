"""The 3D scene through the backend's origin (docs/security.md, "3D scene"):
``/scene/`` (page and WebSocket) needs a session with a role, the WebSocket
an Origin of this service, the page runs under its own CSP (scripts by
hash), the workbench's CSP frames nothing else, and viser listens on
loopback only."""

from __future__ import annotations

import base64
import hashlib
import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from modd_backend import Settings
from modd_backend.app import start_scene
from modd_backend.scene import SceneServer
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Origin, Subprotocol

from .conftest import ADMIN_PASSWORD
from .served import serve

REPO = Path(__file__).resolve().parents[2]
VISER = f"viser-v{importlib.metadata.version('viser')}"


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("scene") / "data",
        initial_admin_password=ADMIN_PASSWORD,
        zenoh_connect=(),
        scene_port=0,
        ws_recheck_s=0.2,
    )
    with serve(settings) as url:
        make_users(url)
        yield url


def make_users(url: str) -> None:
    """``nobody`` (no role) and ``sci`` (scientist), password ``pw-NAME-12345``."""
    admin = _login(url, "admin", ADMIN_PASSWORD)
    for name, roles in (("nobody", []), ("sci", ["scientist"])):
        r = httpx.post(
            url + "/api/users",
            headers=_bearer(admin),
            timeout=30,
            json={"username": name, "password": f"pw-{name}-12345", "roles": roles},
        )
        assert r.status_code == 201, r.text


def _bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def _login(base: str, user: str, password: str, cookie: bool = False) -> str:
    body: dict[str, Any] = {"username": user, "password": password}
    if cookie:
        body["session"] = "cookie"
    r = httpx.post(base + "/api/auth/login", json=body, timeout=30)
    assert r.status_code == 200, r.text
    return str(r.cookies["modd_session"] if cookie else r.json()["token"])


def _socket(base: str, headers: dict[str, str], origin: str | None) -> ClientConnection:
    return connect(
        base.replace("http", "ws") + "/scene",
        additional_headers=headers,
        origin=None if origin is None else Origin(origin),
        subprotocols=[Subprotocol(VISER)],
        open_timeout=10,
    )


def test_scene_page_needs_a_session_with_a_role(base: str) -> None:
    assert httpx.get(base + "/scene/", timeout=30).status_code == 401
    nobody = _login(base, "nobody", "pw-nobody-12345")
    assert httpx.get(base + "/scene/", headers=_bearer(nobody), timeout=30).status_code == 403
    sci = _login(base, "sci", "pw-sci-12345")
    r = httpx.get(base + "/scene/", headers=_bearer(sci), timeout=30)
    assert r.status_code == 200 and b"<html" in r.content[:200]
    cookie = _login(base, "sci", "pw-sci-12345", cookie=True)
    r = httpx.get(base + "/scene/", cookies={"modd_session": cookie}, timeout=30)
    assert r.status_code == 200
    # the workbench frames what /api/scene names: the proxy, on this origin
    assert (
        httpx.get(base + "/api/scene", headers=_bearer(sci), timeout=30).json()["url"] == "/scene/"
    )
    # nothing but viser's files: no way out of its folder
    for path in ("/scene/..%2f..%2fetc/passwd", "/scene/nothing.js"):
        assert httpx.get(base + path, headers=_bearer(sci), timeout=30).status_code == 404


def test_scene_page_csp_allows_its_scripts_by_hash_only(base: str) -> None:
    sci = _login(base, "sci", "pw-sci-12345")
    r = httpx.get(base + "/scene/", headers=_bearer(sci), timeout=30)
    policy = r.headers["content-security-policy"]
    directives = {d.split()[0]: d.split()[1:] for d in policy.split("; ")}
    scripts = directives["script-src"]
    assert "'unsafe-inline'" not in scripts and "'unsafe-eval'" not in scripts
    assert "'self'" not in scripts and "'strict-dynamic'" not in scripts
    # oracle: the page's inline bootstrap hashed here, independently
    inline = re.findall(r"<script[^>]*>(.*?)</script>", r.text, re.DOTALL)
    assert inline
    for body in inline:
        digest = base64.b64encode(hashlib.sha256(body.encode()).digest()).decode()
        assert f"'sha256-{digest}'" in scripts
    assert len([s for s in scripts if s.startswith("'sha256-")]) == len(inline) + 1  # + module
    assert directives["frame-ancestors"] == ["'self'"]
    assert directives["default-src"] == ["'none'"]
    assert r.headers["x-frame-options"] == "SAMEORIGIN"
    assert r.headers["x-content-type-options"] == "nosniff"


def test_workbench_csp_not_widened_by_the_scene(base: str) -> None:
    policy = httpx.get(base + "/api/health", timeout=30).headers["content-security-policy"]
    directives = {d.split()[0]: d.split()[1:] for d in policy.split("; ")}
    assert directives["script-src"] == ["'self'"]
    assert directives["frame-src"] == ["'self'"]  # no viser port: the scene is same origin
    assert directives["frame-ancestors"] == ["'none'"]


def test_scene_socket_refuses_foreign_origin_and_no_session(base: str) -> None:
    cookie = {"Cookie": f"modd_session={_login(base, 'sci', 'pw-sci-12345', cookie=True)}"}
    for headers, origin in (
        (cookie, "http://evil.example"),
        ({}, base),
        ({}, None),
        (cookie, None),  # a cookie without an Origin is not honoured
        ({"Cookie": "modd_session=forged"}, base),
    ):
        with pytest.raises(InvalidStatus) as refused:
            _socket(base, headers, origin)
        assert refused.value.response.status_code == 403, (headers, origin)
    nobody = _login(base, "nobody", "pw-nobody-12345")
    with pytest.raises(InvalidStatus):
        _socket(base, _bearer(nobody), None)


def test_scene_socket_relays_viser_and_closes_at_logout(base: str) -> None:
    token = _login(base, "sci", "pw-sci-12345", cookie=True)
    ws = _socket(base, {"Cookie": f"modd_session={token}"}, base)
    try:
        assert ws.subprotocol == VISER
        first = ws.recv(timeout=15)
        assert isinstance(first, bytes) and first  # viser's scene messages (msgpack)
        t0 = time.monotonic()
        r = httpx.post(
            base + "/api/auth/logout",
            cookies={"modd_session": token},
            headers={"X-CSRF-Token": _csrf(base, token)},
            timeout=30,
        )
        assert r.status_code == 204
        with pytest.raises(ConnectionClosed) as closed:
            while time.monotonic() - t0 < 5:
                ws.recv(timeout=5)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 4401
        assert time.monotonic() - t0 < 1.5
    finally:
        ws.close()


def _csrf(base: str, token: str) -> str:
    r = httpx.get(base + "/api/auth/me", cookies={"modd_session": token}, timeout=30)
    return str(r.json()["csrf"])


def test_viser_listens_on_loopback_only(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="loopback"):
        SceneServer("0.0.0.0", 0)
    # the backend bound everywhere (a container) still keeps viser on loopback
    scene = start_scene(Settings(data_dir=tmp_path, host="0.0.0.0", scene_port=0), None)  # type: ignore
    try:
        assert scene.server.host == "127.0.0.1"
    finally:
        scene.server.stop()


def test_viser_port_answers_the_proxy_alone() -> None:
    """A page or a process going to viser's own loopback port, around the
    proxy, gets 403 on the page and on the WebSocket (no secret, or an
    Origin); the proxy's secret opens it."""
    from modd_backend.scenegate import SECRET_HEADER

    scene = SceneServer("127.0.0.1", 0)
    try:
        url = f"http://127.0.0.1:{scene.port}"
        assert httpx.get(url + "/", timeout=30).status_code == 403
        ok = httpx.get(url + "/", headers={SECRET_HEADER: scene.secret}, timeout=30)
        assert ok.status_code == 200 and b"<html" in ok.content.lower()
        for headers, origin in (
            ({}, None),
            ({}, url),
            ({SECRET_HEADER: "guess"}, None),
            ({SECRET_HEADER: scene.secret}, url),
        ):  # a browser: refused
            with pytest.raises(InvalidStatus) as refused:
                connect(
                    f"ws://127.0.0.1:{scene.port}",
                    additional_headers=headers,
                    origin=None if origin is None else Origin(origin),
                    subprotocols=[Subprotocol(VISER)],
                    open_timeout=10,
                )
            assert refused.value.response.status_code == 403, (headers, origin)
        with connect(
            f"ws://127.0.0.1:{scene.port}",
            subprotocols=[Subprotocol(VISER)],
            additional_headers={SECRET_HEADER: scene.secret},
            open_timeout=10,
        ) as ws:
            assert ws.subprotocol == VISER
    finally:
        scene.stop()


def test_scene_in_a_browser_under_its_csp(base: str) -> None:
    """Chromium loads the page with a cookie session: viser's client runs
    under the page's CSP and connects its WebSocket through the proxy."""
    node = shutil.which("node")
    modules = REPO / "frontend" / "node_modules"
    if node is None or not (modules / "playwright-core").is_dir():
        pytest.fail("node or the frontend's npm packages are missing (run scripts/setup.sh)")
    proc = subprocess.run(
        [node, str(Path(__file__).with_name("scene_browser.cjs")), base, "sci", "pw-sci-12345"],
        capture_output=True,
        text=True,
        timeout=120,
        env=dict(os.environ, NODE_PATH=str(modules)),
        check=False,
    )
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report.get("status") == 200, (report, proc.stderr[-2000:])
    assert report["connected"] and report["frames"] > 0, report
    assert report["refused"] == [], report  # no script, style or socket refused
    assert report["devControls"] == [], report  # no Save Canvas, Dev Settings, Share shown
    # viser's Gaussian-splat sorter compiles code with Function(): refused
    # (no 'unsafe-eval'); the MoDD scene draws no splats.
    assert all("unsafe-eval" in e for e in report["errors"]), report
