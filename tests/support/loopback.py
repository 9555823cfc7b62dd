"""The project's services on loopback, as separate processes, for tests that
wire several of them together: a zenoh router (a Python session in router
mode, so no zenohd is needed), a watch on the SubBrokers' status keys, and the
workbench backend (``modd-backend``) with a small REST and WebSocket client.

Processes are ``Proc`` of tests/subbroker/subbroker_harness.py: each logs to a
file and is stopped by its PID (SIGTERM, then SIGKILL after a bound).
"""

from __future__ import annotations

import contextlib
import json
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from modd.zenoh_auth import acl
from modd.zenoh_session import ZenohSettings, open_session
from websockets.sync.client import ClientConnection, connect
from websockets.sync.connection import Connection

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))

from subbroker_harness import (  # noqa: E402
    PUBBROKER,
    Proc,
    free_port,
    shared_credentials,
    start_pubbroker,
    wait_port,
)

__all__ = [
    "DEMO",
    "SUBBROKER_CLIENT_TOML",
    "PUBBROKER",
    "REPO",
    "VENV_BIN",
    "Backend",
    "Proc",
    "StatusWatch",
    "free_port",
    "receive_until",
    "router_and_watch",
    "start_signed_in_backend",
    "start_pubbroker",
    "shared_credentials",
    "start_client_subbroker",
    "started",
    "wait_port",
    "zenoh_router",
]

REPO = Path(__file__).resolve().parents[2]
VENV_BIN = Path(sys.executable).parent
#: A SubBroker that joins a router as a client and listens nowhere (docs/subbroker.md).
SUBBROKER_CLIENT_TOML = """model = "{model}"
[link]
endpoint = "127.0.0.1:{link}"
key = "file:{key}"
[zenoh]
mode = "client"
listen = []
connect = ["{router}"]
credentials_dir = "{credentials}"
[delivery]
tcp = false
status_period_s = 0.5
"""
#: The demo mission (one drone, ``usv``) the workbench tests fly.
DEMO = REPO / "metamodel" / "examples" / "demo.modd"


@pytest.fixture
def started() -> Iterator[list[Proc]]:
    """The processes a test starts (append them), stopped last first when it ends.
    A fixture: import it into the test module."""
    procs: list[Proc] = []
    yield procs
    for p in reversed(procs):
        p.stop()


def start_client_subbroker(
    tmp: Path, name: str, model: Path, link: int, key_file: Path | str, router: str
) -> Proc:
    """A SubBroker joined to ``router`` as a client (SUBBROKER_CLIENT_TOML), linked to
    127.0.0.1:``link`` with the key in ``key_file``; ``tmp/NAME.toml``, ``tmp/NAME.log``.
    MODD_LINK_KEY is set to a wrong key: the SubBroker must read its own file."""
    config = tmp / f"{name}.toml"
    config.write_text(
        SUBBROKER_CLIENT_TOML.format(
            model=model,
            link=link,
            key=key_file,
            router=router,
            credentials=shared_credentials().dir,
        )
    )
    cmd = [str(VENV_BIN / "modd-subbroker"), "--config", str(config)]
    return Proc(name, cmd, tmp / f"{name}.log", env={"MODD_LINK_KEY": "not-the-link-key"})


@contextlib.contextmanager
def zenoh_router(port: int, config: dict[str, Any] | None = None) -> Iterator[Any]:
    """A zenoh router listening on tcp/127.0.0.1:port, in this process, with
    the authentication and access control of a SubBroker's (every drone), or
    those of ``config`` (a zenohd configuration: its dictionary_file and
    access_control)."""
    dictionary = str(shared_credentials().dictionary)
    rules = acl(None)
    if config is not None:
        dictionary = config["transport"]["auth"]["usrpwd"]["dictionary_file"]
        rules = config["access_control"]
    session = open_session(
        ZenohSettings(
            mode="router",
            listen=(f"tcp/127.0.0.1:{port}",),
            dictionary_file=dictionary,
            access_control=rules,
            extra={"scouting/gossip/enabled": "false"},
        )
    )
    try:
        yield session
    finally:
        session.close()  # type: ignore[no-untyped-call]


class StatusWatch:
    """The last ``modd/<drone>/status`` document of every drone, seen from a session."""

    def __init__(self, session: Any) -> None:
        self.last: dict[str, dict[str, Any]] = {}
        self._lock = threading.Lock()
        self._sub = session.declare_subscriber("modd/*/status", self._on_sample)

    def _on_sample(self, sample: Any) -> None:
        status = json.loads(sample.payload.to_bytes())
        with self._lock:
            self.last[str(status["drone"])] = status

    def get(self, drone: str) -> dict[str, Any] | None:
        with self._lock:
            return self.last.get(drone)

    def wait(
        self, drone: str, pred: Callable[[dict[str, Any]], bool], timeout_s: float
    ) -> dict[str, Any]:
        """The first status of ``drone`` for which ``pred`` holds; fails with the last one."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            status = self.get(drone)
            if status is not None and pred(status):
                return status
            time.sleep(0.1)
        raise AssertionError(
            f"no status of {drone} as expected within {timeout_s} s; last: {self.get(drone)}"
        )

    def close(self) -> None:
        self._sub.undeclare()


class Backend:
    """A running ``modd-backend`` process and a signed-in client of it."""

    def __init__(self, proc: Proc, port: int) -> None:
        self.proc, self.port = proc, port
        self.base = f"http://127.0.0.1:{port}"
        self.token = ""

    @classmethod
    def start(
        cls, tmp: Path, zenoh_connect: str, admin_password: str, extra: list[str] | None = None
    ) -> Backend:
        port = free_port()
        argv = [
            str(VENV_BIN / "modd-backend"),
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--data",
            str(tmp / "backend"),
            "--zenoh-connect",
            zenoh_connect,
            "--admin-password",
            admin_password,
            "--frontend",
            str(tmp / "no-frontend"),
            "--scene-port",
            "-1",
            "--zenoh-credentials",
            str(shared_credentials().cred_file("backend")),
            "--deploy-key",
            str(shared_credentials().deploy_key_file),
            *(extra or []),
        ]
        return cls(Proc("backend", argv, tmp / "backend.log"), port)

    def sign_in(self, password: str, timeout_s: float = 90.0) -> None:
        """Waits until the backend answers, then signs in as ``admin``."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and self.proc.alive():
            with contextlib.suppress(httpx.TransportError):
                r = httpx.post(
                    f"{self.base}/api/auth/login",
                    timeout=5,
                    json={"username": "admin", "password": password},
                )
                assert r.status_code == 200, r.text
                self.token = r.json()["token"]
                return
            time.sleep(0.2)
        raise AssertionError(f"the backend never answered on {self.base}:\n{self.proc.log()}")

    def request(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        headers = {"Authorization": f"Bearer {self.token}"}
        return httpx.request(
            method, f"{self.base}/api{path}", headers=headers, timeout=30, **kwargs
        )

    def stream(self, drone: str) -> ClientConnection:
        """The live stream WebSocket of ``drone``."""
        ws = connect(f"ws://127.0.0.1:{self.port}/api/drones/{drone}/stream", open_timeout=10)
        ws.send(json.dumps({"op": "auth", "token": self.token}))  # never in the URL
        return ws


def receive_until(
    ws: Connection, pred: Callable[[dict[str, Any]], bool], timeout_s: float = 20.0
) -> list[dict[str, Any]]:
    """Messages received until one satisfies ``pred`` (included, last)."""
    got: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            msg = json.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        except TimeoutError:
            break
        got.append(msg)
        if pred(msg):
            return got
    raise AssertionError(f"the expected message never came within {timeout_s} s; got {got[-5:]}")


@contextlib.contextmanager
def router_and_watch() -> Iterator[tuple[str, StatusWatch]]:
    """A zenoh router on a free loopback port (its endpoint) and a watch on the
    SubBrokers' status keys through it; for tests that also run the PubBroker."""
    assert PUBBROKER.exists(), f"{PUBBROKER} is not built: run make build (make test does)"
    port = free_port()
    with zenoh_router(port) as session:
        watch = StatusWatch(session)
        try:
            yield f"tcp/127.0.0.1:{port}", watch
        finally:
            watch.close()


def start_signed_in_backend(tmp: Path, router: str, password: str, started: list[Proc]) -> Backend:
    """The workbench joined to ``router`` (deploys time out after 8 s), in ``started``,
    signed in as its admin."""
    backend = Backend.start(tmp, router, password, ["--deploy-timeout", "8"])
    started.append(backend.proc)
    backend.sign_in(password)
    return backend
