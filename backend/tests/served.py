"""A backend served by uvicorn in a thread of the test process, on a free
loopback port: real sockets for WebSocket and latency tests."""

from __future__ import annotations

import io
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import uvicorn
from modd.ports import free_port
from modd_backend import Settings, create_app
from modd_backend.cli import server_options


@contextmanager
def serve(settings: Settings, **config: Any) -> Iterator[str]:
    """Base URL (http://127.0.0.1:PORT) of the running backend."""
    port = free_port()
    server = uvicorn.Server(
        uvicorn.Config(
            create_app(settings, out=io.StringIO()),
            host="127.0.0.1",
            port=port,
            **{**server_options(settings), **config},
        )
    )
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started:
        assert thread.is_alive() and time.monotonic() < deadline, "uvicorn did not start"
        time.sleep(0.05)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(30)
