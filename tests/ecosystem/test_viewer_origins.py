"""A web page of another origin, in headless Chromium, in a browser where the
operator is signed in to the workbench, reads nothing from the Foxglove live
server, the replay server or viser: not through the backend's proxies
(Origin refused, even holding a valid ticket), not on their own loopback
ports (TLS that no browser trusts; viser's per-server secret). The
workbench's own origin, with a ticket or its cookie, reads all three (the
control that the probe can see frames). docs/security.md."""

from __future__ import annotations

import functools
import http.server
import importlib.metadata
import json
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from ecosystem_support import foxglove_links, node_json
from mcap.writer import Writer
from modd.ports import free_port
from modd_backend import Settings
from served import serve

PASSWORD = "pw-12345678"
FOXGLOVE = ["foxglove.sdk.v1"]
VISER = [f"viser-v{importlib.metadata.version('viser')}"]


def _archive(folder: Path) -> None:
    folder.mkdir(parents=True)
    with open(folder / "minute.mcap", "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("modd.Sample", "jsonschema", b'{"type":"object"}')
        cid = w.register_channel("usv.ctd.temperature", "json", sid, {})
        for k in range(100):
            t = 1_795_000_000_000_000_000 + k * 100_000_000
            w.add_message(cid, t, json.dumps({"value": k}).encode(), t)
        w.finish()  # type: ignore[no-untyped-call]


@pytest.fixture(scope="module")
def foreign(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A page on another origin (127.0.0.2): an empty directory served."""
    root = tmp_path_factory.mktemp("foreign")
    (root / "index.html").write_text("<!doctype html><title>elsewhere</title>")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(root))
    server = http.server.ThreadingHTTPServer(("127.0.0.2", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.2:{server.server_address[1]}/"
    finally:
        server.shutdown()
        thread.join(10)
        server.server_close()


def _sockets(base: str, links: dict[str, Any], ports: dict[str, int]) -> list[dict[str, Any]]:
    host = base.removeprefix("http://")
    return [
        {"name": "live proxy (cookie)", "url": f"ws://{host}/foxglove/live", "protocols": FOXGLOVE},
        {"name": "live proxy (ticket)", "url": links["live"], "protocols": FOXGLOVE},
        {"name": "replay proxy (ticket)", "url": links["replay"], "protocols": FOXGLOVE},
        {"name": "scene proxy (cookie)", "url": f"ws://{host}/scene", "protocols": VISER},
        *(
            {
                "name": f"{n} port {scheme}",
                "url": f"{scheme}://127.0.0.1:{p}",
                "protocols": VISER if n == "viser" else FOXGLOVE,
            }
            for n, p in ports.items()
            for scheme in ("ws", "wss")
        ),
    ]


def test_a_foreign_page_reads_nothing_from_any_viewer_server(tmp_path: Path, foreign: str) -> None:
    _archive(tmp_path / "archives" / "usv")
    ports = {"live": free_port(), "replay": free_port(), "viser": free_port()}
    settings = Settings(
        data_dir=tmp_path / "data",
        initial_admin_password=PASSWORD,
        zenoh_connect=(f"tcp/127.0.0.1:{free_port()}",),  # no router: no data
        archive_dir=tmp_path / "archives",
        foxglove_port=ports["live"],
        foxglove_replay_port=ports["replay"],
        scene_port=ports["viser"],
    )
    with serve(settings) as base:
        token = httpx.post(
            f"{base}/api/auth/login", timeout=30, json={"username": "admin", "password": PASSWORD}
        ).json()["token"]
        r = httpx.post(
            f"{base}/api/drones/usv/archives/minute.mcap/replay",
            timeout=30,
            json={"autoplay": True},
            headers={"Authorization": f"Bearer {token}"},
        )
        assert r.status_code == 200, r.text
        login = (base, "admin", PASSWORD)

        stolen = foxglove_links(base, "admin", PASSWORD)  # valid tickets, wrong origin
        got = node_json(
            "origin_probe.cjs",
            foreign,
            "3",
            json.dumps(_sockets(base, stolen, ports)),
            *login,
            timeout=90,
        )
        assert "fatal" not in got, got
        assert len(got) == 10
        for name, seen in got.items():
            assert seen["frames"] == 0 and not seen["opened"], (name, seen)

        own = foxglove_links(base, "admin", PASSWORD)
        mine = [
            s
            for s in _sockets(base, own, ports)
            if "proxy" in s["name"] and s["name"] != "live proxy (cookie)"
        ]  # the cookie path is the scene's
        got = node_json(
            "origin_probe.cjs", f"{base}/api/health", "3", json.dumps(mine), *login, timeout=90
        )
        for name, seen in got.items():
            assert seen["opened"] and seen["frames"] > 0, (name, seen)
