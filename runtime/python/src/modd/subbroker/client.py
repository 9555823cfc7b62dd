"""Asking a SubBroker over zenoh: dynamic subscriptions and deploys. A get
that finds no queryable returns no reply at once; here silence is an error
(:class:`NoReply`), never an empty success.

>>> ask = {"topic": "usv.a.x", "period_s": "4.0", "aggregation": "AVERAGE"}
>>> request(session, subscribe_key("usv"), ask)["status"]       # doctest: +SKIP
'ACCEPTED'
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import zenoh


class NoReply(RuntimeError):
    """No SubBroker answered (none running for this drone, or not reachable)."""


def request(
    session: zenoh.Session, key: str, payload: dict[str, Any], timeout_s: float = 10.0
) -> dict[str, Any]:
    """Send ``payload`` (JSON) to the queryable at ``key``; the first reply as
    a dict. Raises NoReply on silence, RuntimeError on a zenoh error reply."""
    replies = session.get(key, payload=json.dumps(payload), timeout=timeout_s)
    for reply in replies:
        if reply.ok is None:
            err = reply.err
            text = err.payload.to_string() if err is not None else "unknown"
            raise RuntimeError(f"{key}: error reply: {text}")
        data = json.loads(reply.ok.payload.to_bytes())
        if not isinstance(data, dict):
            raise RuntimeError(f"{key}: reply is not a JSON object")
        return data
    raise NoReply(f"no SubBroker answered on {key} within {timeout_s} s")
