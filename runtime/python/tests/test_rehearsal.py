"""A rehearsed outage (modd up --simulate, `modd link cut`): while the rehearsal
folder holds link-cut, the SubBroker's link client does not connect to the
PubBroker and drops a link that is up; removed, it connects again at once."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from modd.subbroker.config import LinkOptions
from modd.subbroker.link import LinkClient
from modd.subbroker.rehearsal import CutSwitch, is_cut, set_cut


class _Listener:
    """Accepts connections and holds them (a PubBroker that never answers)."""

    def __init__(self) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.conns: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)

    def closed_by_peer(self, conn: socket.socket, timeout_s: float) -> bool:
        conn.settimeout(0.1)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                if conn.recv(4096) == b"":
                    return True
            except TimeoutError:
                continue
            except OSError:
                return True
        return False


class _Handler:
    def on_connect(self, ok: Any, rtt_s: float | None) -> None:
        return None

    def on_config_acked(self, config: Any, ack: Any) -> None: ...

    def on_windows(self, windows: Any) -> None: ...

    def on_status(self, status: Any) -> None: ...


def _wait(cond: Callable[[], bool], timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if cond():
            return True
        time.sleep(0.02)
    return cond()


def test_a_cut_link_stays_down_until_restored(tmp_path: Path) -> None:
    server = _Listener()
    set_cut(tmp_path, True)
    options = LinkOptions(connect_timeout_s=0.5, backoff_initial_s=0.05, backoff_max_s=5.0)
    client = LinkClient(("127.0.0.1", server.port), b"k", options, _Handler())
    client.cut = CutSwitch(tmp_path, check_s=0.05)
    client.start()
    try:
        time.sleep(1.0)
        assert server.conns == [] and client.stats.state == "cut"
        set_cut(tmp_path, False)
        assert _wait(lambda: len(server.conns) == 1, 2.0), "no reconnect after the restore"
        set_cut(tmp_path, True)
        assert server.closed_by_peer(server.conns[0], 3.0), "the link was not dropped by the cut"
        time.sleep(0.5)
        assert len(server.conns) == 1  # and stays down
        set_cut(tmp_path, False)
        assert _wait(lambda: len(server.conns) == 2, 2.0)
    finally:
        client.stop()
        server.sock.close()


def test_the_switch_is_a_file(tmp_path: Path) -> None:
    assert not is_cut(tmp_path)
    set_cut(tmp_path, True)
    set_cut(tmp_path, True)  # twice is fine
    assert is_cut(tmp_path) and (tmp_path / "link-cut").exists()
    set_cut(tmp_path, False)
    set_cut(tmp_path, False)
    assert not is_cut(tmp_path)
