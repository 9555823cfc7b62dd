"""A source churning connections to a zenoh port (issue 38): one address opens
connections as fast as it can, never says a word, holds up to ``hold`` of them and
closes the oldest (``hold`` 0: closes each at once). Counts what it opened and how many
the other side turned away (closed at once, or the SubBroker's gate's refusal line)."""

from __future__ import annotations

import collections
import socket
import threading
import time
from dataclasses import dataclass, field

from modd.zenoh_gate_policy import REFUSAL_MARK


@dataclass
class Churner:
    port: int
    source: str = "127.0.0.2"
    hold: int = 0
    threads: int = 1  # each holds up to ``hold``
    opened: int = 0
    refused: int = 0  # answered with the gate's line
    errors: int = 0  # connect failed (backlog full, no ports left)
    reasons: set[str] = field(default_factory=set)
    _stop: threading.Event = field(default_factory=threading.Event)
    _threads: list[threading.Thread] = field(default_factory=list)

    def __enter__(self) -> Churner:
        for _ in range(self.threads):
            self._threads.append(threading.Thread(target=self._run, daemon=True))
            self._threads[-1].start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(10)

    def _run(self) -> None:
        held: collections.deque[socket.socket] = collections.deque()
        try:
            while not self._stop.is_set():
                s = self._one()
                if s is None:
                    continue
                if self.opened % 16 == 0:  # one in 16 waits to read what it is told
                    self._close(s, wait_s=0.2)
                    continue
                held.append(s)
                while len(held) > self.hold:
                    self._close(held.popleft())
        finally:
            while held:
                self._close(held.popleft())

    def _one(self) -> socket.socket | None:
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.settimeout(1.0)
        try:
            s.bind((self.source, 0))
            s.connect(("127.0.0.1", self.port))
        except OSError:
            s.close()
            self.errors += 1
            time.sleep(0.001)
            return None
        self.opened += 1
        return s

    def _close(self, s: socket.socket, wait_s: float = 0.0) -> None:
        s.settimeout(wait_s) if wait_s else s.setblocking(False)
        try:
            said = s.recv(512)
            if said.startswith(REFUSAL_MARK):
                self.refused += 1
                self.reasons.add(said.decode(errors="replace").split(":")[1].strip())
        except OSError:
            pass
        s.close()
