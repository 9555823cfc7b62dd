"""Deploy requests behind ``modd/<drone>/deploy``: the payload carries a
model; it is validated here, then planned and sent to the PubBroker by the
SubBroker, which replies only after the PubBroker's CONFIG_ACK (or with the
error or the timeout). docs/subbroker.md gives the request and reply shapes.

>>> parse_request(b'{"text": "oops"}', "usv").reply["status"]
'INVALID'
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

from modd_model import load_text

from .request import MAX_DEPLOY_BYTES, read_request

DEFAULT_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class DeployRequest:
    """A parsed request: ``model`` when it can be planned, else the ``reply``."""

    model: dict[str, Any] | None
    timeout_s: float = DEFAULT_TIMEOUT_S
    reply: dict[str, Any] = field(default_factory=dict)
    warnings: list[dict[str, Any]] = field(default_factory=list)
    #: who asked for what: project_id, revision, nonce, deployed_by (as sent)
    fields: dict[str, Any] = field(default_factory=dict)


def _error(status: str, reason: str, **more: Any) -> DeployRequest:
    return DeployRequest(None, reply={"status": status, "reason": reason, **more})


def parse_request(
    payload: bytes, drone: str, verify: Callable[[dict[str, Any]], str | None] | None = None
) -> DeployRequest:
    """Read a deploy payload: ``{"model": {...}}`` (the JSON document) or
    ``{"text": "...", "format": "modd"|"json", "filename": "..."}``, with an
    optional ``"timeout_s"``. ``verify`` (the SubBroker's signature and nonce
    check, modd_model.signing) gives the reason to refuse it, UNAUTHORISED,
    before anything else is read. Never raises for bad input."""
    request, problem = read_request(payload or b"null", MAX_DEPLOY_BYTES)
    if request is None:
        return _error("ERROR", problem or "unreadable request")
    if verify is not None and (refused := verify(request)) is not None:
        return _error("UNAUTHORISED", refused)
    timeout = request.get("timeout_s", DEFAULT_TIMEOUT_S)
    if not isinstance(timeout, int | float) or isinstance(timeout, bool) or timeout <= 0:
        return _error("ERROR", "timeout_s must be a positive number of seconds")
    filename = str(request.get("filename", "<deploy>"))
    fmt: Literal["modd", "json"]
    if "model" in request:
        text, fmt = json.dumps(request["model"]), "json"
    elif isinstance(request.get("text"), str):
        text = request["text"]
        asked = request.get("format", "modd")
        if asked not in ("modd", "json"):
            return _error("ERROR", f"format {asked!r}: expected modd or json")
        fmt = "json" if asked == "json" else "modd"
    else:
        return _error("ERROR", "the request carries neither 'model' nor 'text'")
    result = load_text(text, filename, fmt)
    diagnostics = [d.to_json() for d in result.diagnostics]
    if not result.ok or result.model is None:
        errors = [d for d in diagnostics if d.get("severity") == "error"]
        return _error("INVALID", f"the model has {len(errors)} error(s)", diagnostics=diagnostics)
    name = result.model["drone"]["name"]
    if name != drone:
        reason = f"the model is for drone {name!r}; this SubBroker serves {drone!r}"
        return _error("REJECTED", reason)
    if not result.model.get("subscribers"):
        return _error("REJECTED", "the model has no subscriptions: nothing to send over the link")
    kept = ("project_id", "revision", "nonce", "deployed_by")
    meta: dict[str, Any] = {k: request[k] for k in kept if k in request}
    return DeployRequest(result.model, float(timeout), warnings=diagnostics, fields=meta)
