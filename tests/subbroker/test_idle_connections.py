"""Idle connections to the SubBroker's zenoh port (issue 28, docs/security.md "Idle
connections"): 400 loopback sockets that connect and never say a word do not keep a viewer
from opening an authenticated session within 2 s, and the SubBroker closes each of them once
its accept timeout has passed. Against the real PubBroker and SubBroker CLI."""

from __future__ import annotations

import contextlib
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from modd.zenoh_gate_policy import REFUSAL_MARK
from modd.zenoh_session import client_settings, open_session, wait_connected
from subbroker_harness import (
    free_port,
    model_copy,
    processes,
    shared_credentials,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

IDLE = 400
#: The idle sockets' address: past the accept gate's per-source bound (docs/security.md,
#: "Connections per source") the gate closes them at once; the viewer is on 127.0.0.1.
STRANGER = "127.0.0.2"


@contextlib.contextmanager
def idle_sockets(port: int, n: int) -> Iterator[list[socket.socket]]:
    socks: list[socket.socket] = []
    try:
        for _ in range(n):  # from another address than the viewer's (a stranger's)
            s = socket.create_connection(
                ("127.0.0.1", port), timeout=5, source_address=(STRANGER, 0)
            )
            socks.append(s)
        yield socks
    finally:
        for s in socks:
            s.close()


def viewer_connects_in(port: int) -> float:
    """Seconds from opening a viewer's session to its link with the SubBroker."""
    cred = shared_credentials().cred_file("viewer")
    start = time.monotonic()
    session = open_session(client_settings(f"tcp/127.0.0.1:{port}", cred))
    try:
        assert wait_connected(session, 15.0), "the viewer never connected"
        return time.monotonic() - start
    finally:
        session.close()  # type: ignore[no-untyped-call]


def closed_by_peer(s: socket.socket) -> bool:
    s.setblocking(False)
    try:
        while said := s.recv(4096):  # the gate's refusal line, then the close
            assert said.startswith(REFUSAL_MARK), said
        return True
    except BlockingIOError:
        return False
    except OSError:
        return True  # reset


def test_400_idle_connections_do_not_keep_a_viewer_out(tmp_path: Path) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp_path, "scenario1.modd")
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport))
    with processes(pb, sb):
        wait_port(zport)
        assert sb.wait_log("config 1 running", 15), sb.log()
        assert viewer_connects_in(zport) < 2.0  # the baseline
        with idle_sockets(zport, IDLE) as socks:
            time.sleep(0.2)  # every one accepted, waiting for its handshake
            took = viewer_connects_in(zport)
            assert took < 2.0, f"a viewer took {took:.2f} s behind {IDLE} idle connections"
            # each idle one is closed by the SubBroker once its accept timeout (2 s) is over
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline and not all(closed_by_peer(s) for s in socks):
                time.sleep(0.2)
            assert all(closed_by_peer(s) for s in socks)
            # an attacker opening them again at once: the viewer still gets in
            with idle_sockets(zport, IDLE):
                time.sleep(0.2)
                took = viewer_connects_in(zport)
                assert took < 2.0, f"a viewer took {took:.2f} s behind a second wave"
        assert sb.alive() and pb.alive()
