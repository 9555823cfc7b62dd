"""The backend's one zenoh session (peer mode, multicast scouting off,
explicit endpoints) and the two things done with it: queries with a timeout,
where silence is a failure, and subscriptions delivering to a callback.

>>> bridge = ZenohBridge.open(connect=("tcp/127.0.0.1:7447",))   # doctest: +SKIP
>>> bridge.query("modd/usv/deploy", b"{...}", timeout_s=10)      # doctest: +SKIP
QueryResult(ok=True, payload=b'{"status": "acked", ...}', error=None)
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import zenoh


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


def zenoh_config(connect: tuple[str, ...], listen: tuple[str, ...]) -> zenoh.Config:
    c = zenoh.Config()
    c.insert_json5("mode", '"peer"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("scouting/delay", "0")
    c.insert_json5("connect/endpoints", json.dumps(list(connect)))
    c.insert_json5("listen/endpoints", json.dumps(list(listen)))
    return c


class ZenohBridge:
    def __init__(self, session: zenoh.Session) -> None:
        self._session = session

    @classmethod
    def open(cls, connect: tuple[str, ...] = (), listen: tuple[str, ...] = ()) -> ZenohBridge:
        """Opens at once; peers are connected in the background when they appear."""
        return cls(zenoh.open(zenoh_config(connect, listen)))

    def query(self, key: str, payload: bytes, timeout_s: float) -> QueryResult:
        """Blocking ``get``; call it from a worker thread."""
        replies = self._session.get(key, payload=payload, timeout=timeout_s)
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

        sub: Undeclarable = self._session.declare_subscriber(key, on_sample)
        return sub

    def close(self) -> None:
        self._session.close()  # type: ignore[no-untyped-call]
