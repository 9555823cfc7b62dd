"""A client the SubBroker's zenoh router turns away is told why in its own
words: credentials are needed (or these were refused) and where `make run` and
`modd up` keep a viewer's, not zenoh's "Unable to connect to any of [...]" with
a Rust source path. Against a real router with the SubBroker's authentication
and access control (an in-process zenoh session listening on loopback), and
through the CLI (`modd backfill`) as a user runs it."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from modd.ports import free_port
from modd.zenoh_auth import Credentials, CredentialStore
from modd.zenoh_gate import start_gates
from modd.zenoh_gate_policy import GateLimits
from modd.zenoh_session import ZenohSettings, client_settings, open_session, secured


def _refused(endpoint: str, who: Credentials | None) -> str:
    with pytest.raises(ValueError) as info:
        open_session(client_settings(endpoint, who))
    return str(info.value)


def test_no_credentials_says_they_are_needed_and_where(
    router: tuple[str, CredentialStore, Any],
) -> None:
    endpoint, _, _ = router
    said = _refused(endpoint, None)
    assert f"the router at {endpoint} needs credentials and none were given" in said
    assert "data/credentials/viewer.cred" in said and "--credentials" in said
    assert "Unable to connect" not in said and ".rs:" not in said


def test_wrong_credentials_are_named(router: tuple[str, CredentialStore, Any]) -> None:
    endpoint, _, _ = router
    said = _refused(endpoint, Credentials("viewer", "not-the-password"))
    assert "refused the credentials of user 'viewer'" in said and "viewer.cred" in said


def test_nothing_listening_is_not_blamed_on_credentials(unused_endpoint: str) -> None:
    said = _refused(unused_endpoint, None)
    assert "nothing answers at" in said and "needs credentials" not in said


def test_the_right_credentials_open(router: tuple[str, CredentialStore, Any]) -> None:
    endpoint, store, _ = router
    session = open_session(client_settings(endpoint, store.cred_file("viewer")))
    session.close()  # type: ignore[no-untyped-call]


def test_modd_backfill_without_credentials(router: tuple[str, CredentialStore, Any]) -> None:
    endpoint, _, _ = router
    res = subprocess.run(
        [
            str(Path(sys.executable).parent / "modd"),
            "backfill",
            "--drone",
            "usv",
            "--subscriber",
            "sub_1",
            "--gaps",
            "--connect",
            endpoint,
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env={"PATH": "/usr/bin:/bin"},
    )
    assert res.returncode == 2
    assert "needs credentials" in res.stderr and "viewer.cred" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr and ".rs:" not in res.stderr


def test_a_router_closing_every_new_connection_is_not_blamed_on_credentials(
    tmp_path: Path,
) -> None:
    """A router whose `accept_pending` is reached (connections that never authenticate)
    closes every new connection at once, real clients too: the viewer is told so, not that
    its credentials were refused, keeps trying meanwhile and opens once there is room."""
    store = CredentialStore(tmp_path / "credentials")
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    settings = secured(ZenohSettings(mode="router", listen=(endpoint,)), store, "subbroker", "usv")
    limits = {"transport/unicast/accept_pending": "8", "transport/unicast/accept_timeout": "60000"}
    router = open_session(replace(settings, extra={**settings.extra, **limits}))
    idle: list[socket.socket] = []
    try:
        idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(12)]
        time.sleep(0.3)
        viewer = client_settings(endpoint, store.cred_file("viewer"))
        with pytest.raises(ValueError) as info:
            open_session(viewer, busy_wait_s=1.0)
        said = str(info.value)
        assert "closes every new connection at once" in said, said
        assert "accept_pending" in said and "credentials were not checked" in said
        assert "refused the credentials" not in said

        # room again (the flood ends) while the viewer is trying: it opens
        def room() -> None:
            for s in idle:
                s.close()

        threading.Timer(1.5, room).start()
        began = time.monotonic()
        session = open_session(viewer, busy_wait_s=10.0)
        took = time.monotonic() - began
        session.close()  # type: ignore[no-untyped-call]
        print(f"opened {took:.2f} s after the first try, 1.5 s after which there was room")
        assert took < 6.0
    finally:
        for s in idle:
            s.close()
        router.close()  # type: ignore[no-untyped-call]


def test_a_viewer_whose_address_the_gate_throttles_is_told_so(tmp_path: Path) -> None:
    """Behind the SubBroker's accept gate (modd.zenoh_gate), a viewer on an address that
    already has ``per_source_pending`` connections being set up is told that the gate
    refuses new connections from its address, and the bound's name, not that its
    credentials were refused; once those connections are over it opens."""
    store = CredentialStore(tmp_path / "credentials")
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    settings = secured(ZenohSettings(mode="router", listen=(endpoint,)), store, "subbroker", "usv")
    settings = replace(settings, gate=GateLimits(per_source_pending=4))
    inner, gates = start_gates(settings)
    router = open_session(inner)
    idle: list[socket.socket] = []
    try:
        idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(4)]
        time.sleep(0.3)
        viewer = client_settings(endpoint, store.cred_file("viewer"))
        with pytest.raises(ValueError) as info:
            open_session(viewer, busy_wait_s=0.5)
        said = str(info.value)
        assert "refuses new connections from this address" in said, said
        assert "per_source_pending: 4 connections of 127.0.0.1 being set up" in said
        assert "credentials were not checked" in said and "refused the credentials" not in said

        def room() -> None:
            for s in idle:
                s.close()

        threading.Timer(0.5, room).start()
        session = open_session(viewer, busy_wait_s=10.0)
        session.close()  # type: ignore[no-untyped-call]
    finally:
        for s in idle:
            s.close()
        router.close()  # type: ignore[no-untyped-call]
        for gate in gates:
            gate.stop()
