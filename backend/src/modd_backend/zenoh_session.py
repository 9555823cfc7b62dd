"""The backend's one zenoh session and the two things done with it: queries
with a timeout, where silence is a failure, and subscriptions delivering to a
callback.

The session is a *client* of the SubBroker's router (multicast scouting off,
explicit endpoints) that gives the ``backend`` identity's user name and
password (a ``.cred`` file, docs/security.md), so every message goes through
the router's access control. A client cannot open while no router listens:
the session keeps trying in the background, and subscriptions asked meanwhile
are declared once it is open. (Listening, ``zenoh_listen``, makes it a peer.)

>>> zs = ZenohSession.open(connect=("tcp/127.0.0.1:7447",))   # doctest: +SKIP
>>> zs.query("modd/usv/deploy", b"{...}", timeout_s=10)      # doctest: +SKIP
QueryResult(ok=True, payload=b'{"status": "acked", ...}', error=None)
"""

from __future__ import annotations

import json
import logging
import os
import stat
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import zenoh
from modd.zenoh_recovery import values_subscriber
from modd_contracts import keys


class Undeclarable(Protocol):
    def undeclare(self) -> None: ...


@dataclass(frozen=True)
class QueryResult:
    """The first reply: ``ok`` with its payload, or the error (error reply,
    timeout, or no queryable at all)."""

    ok: bool
    payload: bytes
    error: str | None = None

    def json(self) -> Any:
        try:
            return json.loads(self.payload)
        except (ValueError, UnicodeDecodeError):
            return {"raw": self.payload.decode("utf-8", "replace")}


log = logging.getLogger("modd_backend.zenoh")
MAX_SECRET_BYTES = 64 * 1024
RETRY_S = 0.5
#: When the backend listens: bounds against connections that never authenticate (the mirror of
#: modd.zenoh_session.LISTENER_LIMITS; docs/security.md, "Idle connections").
LISTENER_LIMITS = {
    "transport/unicast/accept_timeout": "2000",
    "transport/unicast/accept_pending": "2000",
    "transport/unicast/max_sessions": "256",
}


def read_secret(path: Path, what: str) -> str:
    """A small regular file's text (one trailing newline stripped), read
    without following a final symlink: the mirror of modd.zenoh_auth.read_secret."""
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_SECRET_BYTES:
            raise ValueError(
                f"{what} {path}: not a regular file of at most {MAX_SECRET_BYTES} bytes"
            )
        if st.st_mode & 0o077:
            log.warning("%s %s can be read by group or others: chmod 600 it", what, path)
        data = os.read(fd, MAX_SECRET_BYTES)
    finally:
        os.close(fd)
    text = data.decode("utf-8").removesuffix("\n")
    if not text:
        raise ValueError(f"{what} {path}: the file is empty")
    return text


def zenoh_config(
    connect: tuple[str, ...], listen: tuple[str, ...], credentials: Path | None = None
) -> zenoh.Config:
    c = zenoh.Config()
    c.insert_json5("mode", '"peer"' if listen or not connect else '"client"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("scouting/gossip/enabled", "false")
    c.insert_json5("scouting/delay", "0")
    c.insert_json5("connect/endpoints", json.dumps(list(connect)))
    c.insert_json5("listen/endpoints", json.dumps(list(listen)))
    for key, value in LISTENER_LIMITS.items() if listen else ():
        c.insert_json5(key, value)
    if credentials is not None:
        user, sep, password = read_secret(credentials, "zenoh credentials").partition(":")
        if not sep or not user or not password:
            raise ValueError(f"zenoh credentials {credentials}: expected user:password")
        c.insert_json5("transport/auth/usrpwd/user", json.dumps(user))
        c.insert_json5("transport/auth/usrpwd/password", json.dumps(password))
    return c


class _Pending:
    """A subscription asked before the session opened; declared when it does."""

    def __init__(self, owner: ZenohSession, key: str, on_sample: Any) -> None:
        self.owner, self.key, self.on_sample = owner, key, on_sample
        self.real: Undeclarable | None = None

    def undeclare(self) -> None:
        with self.owner._lock:
            self.owner._pending.discard(self)
            real, self.real = self.real, None
        if real is not None:
            real.undeclare()


class ZenohSession:
    def __init__(
        self,
        session: zenoh.Session | None,
        config: Callable[[], zenoh.Config] | None = None,
        where: str = "",
    ) -> None:
        self._session = session
        self._config = config
        self._where = where
        self._lock = threading.Lock()
        self._pending: set[_Pending] = set()
        self._closed = threading.Event()
        self._opener: threading.Thread | None = None

    @classmethod
    def open(
        cls,
        connect: tuple[str, ...] = (),
        listen: tuple[str, ...] = (),
        credentials: Path | None = None,
    ) -> ZenohSession:
        """Opens at once when the router is up, else keeps trying in the background
        (the credentials file is read at each try: it may not be made yet)."""
        opened = cls(
            None, lambda: zenoh_config(connect, listen, credentials), ", ".join(connect + listen)
        )
        if not opened._try_open():
            opened._opener = threading.Thread(
                target=opened._keep_trying, daemon=True, name="modd-zenoh-open"
            )
            opened._opener.start()
        return opened

    def _try_open(self) -> bool:
        assert self._config is not None
        try:
            session = zenoh.open(self._config())
        except zenoh.ZError:
            return False
        except (OSError, ValueError) as exc:  # no credentials file yet, or a bad one
            log.warning("zenoh credentials: %s", exc)
            return False
        with self._lock:
            self._session = session
            pending = list(self._pending)
        for p in pending:
            p.real = _declare(session, p.key, p.on_sample)
        log.info("zenoh session open (%s)", self._where)
        return True

    def _keep_trying(self) -> None:
        log.warning("zenoh router %s not reachable (or credentials refused); retrying", self._where)
        while not self._closed.wait(RETRY_S):
            if self._try_open():
                return

    def query(self, key: str, payload: bytes, timeout_s: float) -> QueryResult:
        """Blocking ``get``; call it from a worker thread."""
        session = self._session
        if session is None:
            return QueryResult(
                False,
                b"",
                f"the zenoh router {self._where} is not reachable "
                "(or refused the backend's credentials)",
            )
        replies = session.get(key, payload=payload, timeout=timeout_s)
        for reply in replies:
            if reply.ok is not None:
                return QueryResult(True, reply.ok.payload.to_bytes())
            err = reply.err.payload.to_bytes() if reply.err is not None else b""
            text = err.decode("utf-8", "replace")
            if text.lower() == "timeout":
                text = f"no reply on {key} within {timeout_s:g} s"
            return QueryResult(False, err, text)
        return QueryResult(False, b"", f"nobody answers on {key} (is the SubBroker running?)")

    def subscribe(self, key: str, callback: Callable[[str, bytes], None]) -> Undeclarable:
        """``callback(key, payload)`` runs on a zenoh thread: it must not block."""

        def on_sample(sample: zenoh.Sample) -> None:
            callback(str(sample.key_expr), sample.payload.to_bytes())

        with self._lock:
            session = self._session
            if session is None:
                pending = _Pending(self, key, on_sample)
                self._pending.add(pending)
                return pending
        sub: Undeclarable = _declare(session, key, on_sample)
        return sub

    def close(self) -> None:
        self._closed.set()
        if self._opener is not None:
            self._opener.join(timeout=5)
        if self._session is not None:
            self._session.close()  # type: ignore[no-untyped-call]


def _declare(session: zenoh.Session, key: str, on_sample: Callable[[zenoh.Sample], None]) -> Any:
    """Delivered values through zenoh's recovery (a value a break in the mesh kept from
    the backend is asked for again: docs/fleet.md); anything else as a plain subscriber."""
    if key == keys.ALL_VALUES:
        return values_subscriber(session, key, on_sample)
    return session.declare_subscriber(key, on_sample)
