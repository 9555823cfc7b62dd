"""What the SubBroker holds of its link (:class:`Link`, whatever the
transport) and the thread that pumps a :class:`~.session.LinkSession`: it
opens the connection, feeds the session what it reads, ticks it, writes out
what it emits, and reconnects when the session ends: at once the first time
after a link that was up a while (tcp), then with exponential backoff.

The transports (``link.py``: tcp; ``dglink.py``: udp and serial) only say how
to open, read, write and close.

>>> link = link_client(config, key, handler, liveness)   # doctest: +SKIP
>>> link.start(); link.send_config(config, 5.0)           # doctest: +SKIP
"""

from __future__ import annotations

import logging
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, Protocol

from modd.link import codec
from modd.link.frames import Config, ConfigAck, Onboard, OnboardAck, ProtocolError

from .config import LinkOptions
from .linkhooks import LinkDown, LinkStats
from .session import LinkSession

log = logging.getLogger("modd.subbroker.link")


class Switch(Protocol):
    """What keeps the link from connecting while it says so: a rehearsal's cut
    (:class:`~.rehearsal.CutSwitch`), another station serving the drone
    (:class:`~.serving.ServingSwitch`)."""

    @property
    def cut(self) -> bool: ...


class Link(Protocol):
    """The link to the PubBroker, as the SubBroker and its backfill manager use it."""

    #: Backfill frames from the PubBroker go here (link thread); ``on_up`` runs after each
    #: (re)connection, so that running backfills are asked for again with their resume point.
    backfill_sink: Callable[[codec.RawFrame], None] | None
    on_up: Callable[[], None] | None

    @property
    def stats(self) -> LinkStats: ...

    @property
    def up(self) -> bool: ...

    def start(self) -> None: ...

    def stop(self) -> None: ...

    def send_frame(self, frame: bytes) -> None:
        """Send one encoded frame (a backfill request or cancel); raises LinkDown."""
        ...

    def send_config(self, config: Config, timeout_s: float) -> ConfigAck:
        """Send CONFIG and wait for its CONFIG_ACK (any thread). Raises LinkDown,
        ConfigRejected or TimeoutError."""
        ...

    def send_onboard(self, msg: Onboard, timeout_s: float) -> OnboardAck:
        """Send ONBOARD and wait for its ONBOARD_ACK (any thread). Raises LinkDown,
        ValueError (too large for the link) or TimeoutError."""
        ...

    def radio_status(self) -> dict[str, Any] | None:
        """A datagram link's figures (docs/subbroker.md, "Status"); None over tcp."""
        ...


class Pump(ABC):
    """Keeps one authenticated link to the PubBroker up, on a daemon thread."""

    #: After a session that was up for ``backoff_max_s`` (a flapping radio, not a peer that
    #: fails at once), the first retry goes at once.
    retry_at_once = True

    def __init__(
        self, session: LinkSession, options: LinkOptions, where: str, thread_name: str
    ) -> None:
        self.session = session
        self._opt = options
        self._where = where
        self._send_lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=thread_name, daemon=True)
        #: While it says cut, no link: a rehearsal's switch (modd up --simulate, rehearsal.py),
        #: or the election of the station serving the drone (serving.py).
        self.cut: Switch | None = None

    # -- what a transport provides --------------------------------------------------

    @abstractmethod
    def _open(self) -> None:
        """Open the transport (a connect or a port); raise OSError when it cannot."""

    @abstractmethod
    def _read(self) -> None:
        """Wait a little for what comes, and feed it to the session."""

    @abstractmethod
    def _write(self, data: bytes) -> None:
        """Send bytes the session queued."""

    @abstractmethod
    def _close(self, stopping: bool) -> None:
        """Close the transport (``stopping``: for good, not to reconnect)."""

    # -- public ------------------------------------------------------------------------

    @property
    def stats(self) -> LinkStats:
        return self.session.stats

    @property
    def backfill_sink(self) -> Callable[[codec.RawFrame], None] | None:
        return self.session.backfill_sink

    @backfill_sink.setter
    def backfill_sink(self, sink: Callable[[codec.RawFrame], None] | None) -> None:
        self.session.backfill_sink = sink

    @property
    def on_up(self) -> Callable[[], None] | None:
        return self.session.on_up

    @on_up.setter
    def on_up(self, hook: Callable[[], None] | None) -> None:
        self.session.on_up = hook

    @property
    def up(self) -> bool:
        return self.session.up

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self._drop("stopping")
        self._close(stopping=True)

    def send_frame(self, frame: bytes) -> None:
        if not self.session.up:
            raise LinkDown(f"the link to {self._where} is down")
        self.session.send(frame)
        self._flush()

    def send_config(self, config: Config, timeout_s: float) -> ConfigAck:
        deadline = time.monotonic() + timeout_s
        if not self.session.wait_up(timeout_s):
            raise LinkDown(f"the link to {self._where} is down")
        future = self.session.submit(config)
        self._flush()
        try:
            return future.result(timeout=max(0.0, deadline - time.monotonic()))
        except FutureTimeout as exc:
            raise TimeoutError(f"no CONFIG_ACK for config {config.config_id}") from exc

    def send_onboard(self, msg: Onboard, timeout_s: float) -> OnboardAck:
        if not self.session.up:
            raise LinkDown(f"the link to {self._where} is down")
        future = self.session.submit_onboard(msg)
        self._flush()
        try:
            return future.result(timeout=timeout_s)
        except FutureTimeout as exc:
            raise TimeoutError(f"no ONBOARD_ACK for config {msg.config_id}") from exc

    def radio_status(self) -> dict[str, Any] | None:
        return None

    # -- thread ------------------------------------------------------------------------

    def _flush(self) -> None:
        with self._send_lock:  # the session's order is the wire's
            for data in self.session.take():
                self._write(data)

    def _is_cut(self) -> bool:
        return self.cut is not None and self.cut.cut

    def _run(self) -> None:
        backoff = self._opt.backoff_initial_s
        while not self._stop.is_set():
            if self._is_cut():  # a rehearsed outage: no connect until it is restored, then at once
                self.stats.state = getattr(self.cut, "state", "cut")
                backoff = 0.0
                self._while_cut()
                continue
            connects, began = self.stats.connects, time.monotonic()
            try:
                self._session()
            except (OSError, ProtocolError) as exc:
                self.stats.last_error = str(exc)
                if not self._stop.is_set():
                    log.warning("link to %s: %s", self._where, exc)
            except Exception as exc:  # a bug must not end the reconnect loop
                self.stats.last_error = f"internal error: {exc}"
                log.exception("link to %s: internal error", self._where)
            finally:
                self._drop("link down")
            lasted = time.monotonic() - began
            if (
                self.retry_at_once
                and self.stats.connects != connects
                and lasted >= self._opt.backoff_max_s
            ):
                backoff = 0.0
            if self._stop.wait(backoff):
                break
            backoff = min(max(backoff * 2, self._opt.backoff_initial_s), self._opt.backoff_max_s)
        self.stats.state = "stopped"

    def _session(self) -> None:
        self.stats.state = "connecting"
        self._open()
        self.session.begin()
        self._flush()
        while not self._stop.is_set():
            if self._is_cut():
                raise LinkDown(getattr(self.cut, "why", "the link was cut for a rehearsal"))
            self._read()
            self._flush()
            self.session.tick()
            self._flush()

    def _while_cut(self) -> None:
        """What the thread does while the link is cut, a turn at a time (a datagram
        link's standby station listens: dglink.py)."""
        self._stop.wait(0.1)

    def _drop(self, reason: str) -> None:
        self.session.close(reason)
        self._close(stopping=False)
