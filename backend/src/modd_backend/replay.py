"""The workbench's replay slot: one ranged-playback Foxglove server
(modd_backend.foxglove_replay) at a time, on the backend's host and
``--foxglove-replay-port``, over an archive file the user picked in the
Archives panel — a closed file, or the one the drone is still writing (its
complete part). Starting another replay replaces the current one. Viewers
reach it at ``/foxglove/replay`` on the backend's port (foxgloveproxy.py)."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .foxglove_replay import ReplayServer, load_recording
from .loopback_tls import LoopbackTls

#: Messages one replay holds in memory at most (≈ 200 B each).
MAX_REPLAY_MESSAGES = 1_000_000
#: Seconds a replay may spend reading its range before it is refused.
REPLAY_LOAD_S = 60.0


@dataclass(frozen=True)
class ReplayInfo:
    url: str
    drone: str
    file: str
    start_ns: int
    end_ns: int
    messages: int
    topics: list[str]
    started_by: str
    autoplay: bool


class ReplaySlot:
    """With ``tls`` the server speaks ``wss://`` only (reached through the
    backend's proxy, foxgloveproxy.py); ``port`` 0: a free port each time."""

    def __init__(
        self,
        host: str,
        port: int,
        max_messages: int = MAX_REPLAY_MESSAGES,
        tls: LoopbackTls | None = None,
    ) -> None:
        self.host, self.port, self.max_messages = host, port, max_messages
        self.tls = tls
        self._lock = threading.Lock()
        self._server: ReplayServer | None = None
        self.info: ReplayInfo | None = None

    def start(
        self,
        drone: str,
        path: Path,
        start_ns: int | None,
        end_ns: int | None,
        user: str,
        *,
        autoplay: bool = False,
    ) -> ReplayInfo:
        """Loads the range (ValueError: nothing in it, or too much), then
        swaps the server; the old one stops first so the port is free."""
        recording = load_recording(
            [path],
            self.max_messages,
            partial=True,
            start_ns=start_ns,
            end_ns=end_ns,
            time_s=REPLAY_LOAD_S,
        )
        with self._lock:
            self._stop_locked()
            server = self._bind(path, recording, autoplay)
            self._server = server
            p = server.player
            self.info = ReplayInfo(
                server.url,
                drone,
                path.name,
                p.start,
                p.end,
                len(p.messages),
                sorted(server.channels),
                user,
                autoplay,
            )
            return self.info

    def _bind(self, path: Path, recording: Any, autoplay: bool) -> ReplayServer:
        """The new server on the slot's port: the SDK frees the port of the one
        just stopped a moment later, so a busy port is retried for up to 3 s."""
        deadline = time.monotonic() + 3.0
        while True:
            try:
                return ReplayServer(
                    [path],
                    self.host,
                    self.port,
                    recording=recording,
                    autoplay=autoplay,
                    tls=self.tls,
                )
            except RuntimeError as exc:  # the SDK's FoxgloveError
                if "in use" not in str(exc) or time.monotonic() > deadline:
                    raise OSError(str(exc)) from None
                time.sleep(0.1)

    def serving_port(self) -> int | None:
        """The port of the replay being served now, or None."""
        with self._lock:
            return None if self._server is None else self._server.port

    def stop(self) -> None:
        with self._lock:
            self._stop_locked()

    def _stop_locked(self) -> None:
        if self._server is not None:
            self._server.stop()
            self._server = None
            self.info = None
