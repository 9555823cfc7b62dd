"""An answer's headers and body leave in one send (coalesce.py, issue 41):
the writes of one loop iteration reach the socket together, nothing waits
past the iteration, close sends first, abort drops; through a real uvicorn
the answers (small, 3 MB, WebSocket) read back whole with httpx and
websockets, and a small answer's headers and body arrive in one read."""

from __future__ import annotations

import asyncio
import json
import socket
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from modd_backend import Settings
from modd_backend.cli import server_options
from modd_backend.coalesce import CoalescingHttpToolsProtocol, CoalescingTransport
from websockets.sync.client import connect

from .conftest import ADMIN_PASSWORD
from .served import serve


class FakeTransport:
    def __init__(self) -> None:
        self.sent: list[list[bytes]] = []
        self.closing = False
        self.events: list[str] = []

    def write(self, data: bytes) -> None:
        self.sent.append([data])

    def writelines(self, lines: list[bytes]) -> None:
        self.sent.append(list(lines))

    def is_closing(self) -> bool:
        return self.closing

    def close(self) -> None:
        self.events.append("close")
        self.closing = True

    def abort(self) -> None:
        self.events.append("abort")
        self.closing = True

    def get_write_buffer_size(self) -> int:
        return 0

    def get_extra_info(self, name: str) -> Any:
        return f"extra:{name}"


def test_writes_of_one_iteration_leave_together_and_no_later() -> None:
    async def run() -> FakeTransport:
        fake = FakeTransport()
        t = CoalescingTransport(fake, asyncio.get_running_loop())  # type: ignore[arg-type]
        buf = bytearray(b"body")
        t.write(b"HTTP/1.1 200 OK\r\n\r\n")
        t.write(buf)
        buf[:] = b"XXXX"  # reused by its writer: the kept copy is unchanged
        t.write(b"")
        assert fake.sent == [] and t.get_write_buffer_size() == 23
        await asyncio.sleep(0)  # the end of the iteration
        assert fake.sent == [[b"HTTP/1.1 200 OK\r\n\r\n", b"body"]]
        t.writelines([b"one"])
        await asyncio.sleep(0)
        assert fake.sent[-1] == [b"one"]
        assert t.get_extra_info("peername") == "extra:peername"
        t.write(b"last")
        t.close()  # sent before the close
        assert fake.sent[-1] == [b"last"] and fake.events == ["close"]
        t.write(b"after")
        await asyncio.sleep(0)  # a closing transport takes nothing more
        assert fake.sent[-1] == [b"last"]
        fake2 = FakeTransport()
        t2 = CoalescingTransport(fake2, asyncio.get_running_loop())  # type: ignore[arg-type]
        t2.write(b"dropped")
        t2.abort()
        await asyncio.sleep(0)
        assert fake2.sent == [] and fake2.events == ["abort"]
        return fake

    asyncio.run(run())


def test_the_service_runs_the_coalescing_protocol() -> None:
    assert (
        server_options(Settings(data_dir=Path("/nonexistent")))["http"]
        is CoalescingHttpToolsProtocol
    )


def _one_read(base: str, path: str) -> bytes:
    host, port = base.removeprefix("http://").split(":")
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
        return s.recv(65536)


def _write_calls() -> int:
    """This process's write system calls so far (a socket's write/writev count; send does not)."""
    with open("/proc/self/io") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("syscw"))


@pytest.mark.skipif(not Path("/proc/self/io").exists(), reason="Linux /proc/self/io")
def test_an_answer_is_one_write_where_plain_uvicorn_makes_two(tmp_path: Path) -> None:
    settings = Settings(data_dir=tmp_path / "data", zenoh_enabled=False)
    calls = {}
    for http in ("httptools", None):  # uvicorn's own protocol: the oracle of two
        with serve(settings, access_log=False, **({"http": http} if http else {})) as base:
            _one_read(base, "/api/health")
            before = _write_calls()
            for _ in range(100):
                assert _one_read(base, "/api/health").startswith(b"HTTP/1.1 200")
            calls[http or "coalescing"] = _write_calls() - before
    assert calls["httptools"] >= 195, calls
    assert 100 <= calls["coalescing"] <= 105, calls


def test_answers_through_uvicorn_are_whole(tmp_path: Path) -> None:
    settings = Settings(
        data_dir=tmp_path / "data", zenoh_enabled=False, initial_admin_password=ADMIN_PASSWORD
    )
    with serve(settings) as base, httpx.Client(base_url=base, timeout=30) as c:
        # headers and body in the first read (two sends would often be two reads)
        first = [_one_read(base, "/api/health") for _ in range(20)]
        assert all(r.startswith(b"HTTP/1.1 200") and r.endswith(b"}") for r in first), first[0]
        token = c.post("/api/auth/login", json={"username": "admin", "password": ADMIN_PASSWORD})
        admin = {"Authorization": f"Bearer {token.json()['token']}"}
        text = "model big {\n  // " + "x" * 3_000_000 + "\n}\n"
        r = c.post("/api/projects", headers=admin, json={"name": "b", "model": {"text": text}})
        assert r.status_code in (201, 413, 422), r.text  # its answer read whole, whatever it is
        for _ in range(50):  # keep-alive: answers stay in order on one connection
            h = c.get("/api/health")
            assert h.status_code == 200 and h.json()["status"] == "ok"
        big = c.get("/openapi.json")
        assert big.status_code == 200 and int(big.headers["content-length"]) == len(big.content)
        json.loads(big.content)


async def _echo(scope: dict[str, Any], receive: Any, send: Any) -> None:
    """A WebSocket echo (the service's streams need zenoh)."""
    if scope["type"] != "websocket":
        return
    await receive()
    await send({"type": "websocket.accept"})
    while True:
        message = await receive()
        if message["type"] != "websocket.receive":
            return
        for _ in range(3):
            await send({"type": "websocket.send", "text": message["text"]})


def test_a_websocket_upgraded_from_it_echoes_in_order(tmp_path: Path) -> None:
    import threading
    import time

    import uvicorn
    from modd.ports import free_port

    port = free_port()
    options = server_options(Settings(data_dir=tmp_path))
    config = uvicorn.Config(_echo, host="127.0.0.1", port=port, lifespan="off", **options)
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    try:
        with connect(f"ws://127.0.0.1:{port}/") as ws:
            for i in range(20):
                ws.send(f"m{i}" * (1 + i * 1000))
            got = [ws.recv(timeout=10) for _ in range(60)]
        assert got == [f"m{i}" * (1 + i * 1000) for i in range(20) for _ in range(3)]
    finally:
        server.should_exit = True
        thread.join(30)
