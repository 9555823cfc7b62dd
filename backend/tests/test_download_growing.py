"""Downloading an archive the drone is still writing (it grows during the
download): every download completes with the bytes the file held when it
began, as many as its Content-Length says (before: the server declared the
size it saw, read on to the end, and cut the connection when the file had
grown: 4 of 300 downloads aborted)."""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx2 as httpx
from modd_backend import Settings

from .conftest import ADMIN_PASSWORD
from .served import serve


def test_downloads_of_a_growing_file_complete(tmp_path: Path) -> None:
    folder = tmp_path / "archives" / "usv"
    folder.mkdir(parents=True)
    path = folder / "writing.mcap"
    path.write_bytes(os.urandom(1024 * 1024))
    stop = threading.Event()

    def write() -> None:  # the PubBroker appending: 8 KiB a millisecond, up to 24 MiB
        with path.open("ab") as f:
            while not stop.wait(0.001) and f.tell() < 24 * 1024 * 1024:
                f.write(os.urandom(8 * 1024))
                f.flush()

    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        scene_port=None,
        initial_admin_password=ADMIN_PASSWORD,
        archive_dir=tmp_path / "archives",
    )
    writer = threading.Thread(target=write)
    with serve(settings) as base:
        token = httpx.post(
            f"{base}/api/auth/login",
            timeout=30,
            json={"username": "admin", "password": ADMIN_PASSWORD},
        ).json()["token"]

        def download(_: int) -> str:
            try:
                r = httpx.get(
                    f"{base}/api/drones/usv/archives/writing.mcap",
                    timeout=60,
                    headers={"Authorization": f"Bearer {token}"},
                )
            except httpx.TransportError as exc:
                return f"aborted: {exc}"
            if r.status_code != 200 or len(r.content) != int(r.headers["content-length"]):
                return f"{r.status_code}, {len(r.content)} bytes"
            with path.open("rb") as f:
                return "ok" if f.read(len(r.content)) == r.content else "not the file's bytes"

        writer.start()
        try:
            with ThreadPoolExecutor(4) as pool:
                results = list(pool.map(download, range(60)))
        finally:
            stop.set()
            writer.join(10)
    assert results == ["ok"] * 60, [r for r in results if r != "ok"][:5]
