"""Signed deploy requests (docs/security.md, "Signed deploys"): the workbench
signs what it sends to ``modd/<drone>/deploy`` with a key it shares with the
SubBroker (made by ``modd up`` or the SubBroker at first start,
``deploy.key``), and the SubBroker applies a deploy only when the signature
holds and its nonce is fresh. Zenoh's access control says who may ask; the
signature says the request came through the workbench's audited path.

The HMAC-SHA256 covers the canonical JSON of the whole request but its
``signature`` (model or text, drone, revision, who deployed, nonce, timeout).

>>> key = b"k" * 32
>>> req = sign_request(key, {"model": {"drone": {"name": "usv"}}, "revision": 3})
>>> NonceGuard().verify(key, req) is None
True
>>> NonceGuard().verify(b"other", req)
'the deploy request is not signed by the workbench (bad signature)'
"""

from __future__ import annotations

import hashlib
import hmac
import json
import secrets
import threading
import time
from collections import OrderedDict
from typing import Any

#: How old (or how far in the future) a signed request may be.
MAX_AGE_S = 300.0
#: Nonces remembered (a request older than MAX_AGE_S is refused anyway).
MAX_NONCES = 100_000
DOMAIN = b"modd-deploy-v1\n"


def _message(request: dict[str, Any]) -> bytes:
    body = {k: v for k, v in request.items() if k != "signature"}
    return DOMAIN + json.dumps(body, sort_keys=True, separators=(",", ":"),
                               ensure_ascii=True).encode()


def signature(key: bytes, request: dict[str, Any]) -> str:
    return hmac.new(key, _message(request), hashlib.sha256).hexdigest()


def sign_request(key: bytes, request: dict[str, Any]) -> dict[str, Any]:
    """``request`` with a fresh ``nonce`` (issue time in ns and 128 random
    bits) and its ``signature``."""
    out = dict(request)
    out["nonce"] = f"{time.time_ns()}-{secrets.token_hex(16)}"
    out["signature"] = signature(key, out)
    return out


class NonceGuard:
    """Verifies signatures and refuses a nonce seen before (replay) or out
    of the time window. Thread-safe; memory bounded by MAX_NONCES."""

    def __init__(self, max_age_s: float = MAX_AGE_S) -> None:
        self._max_age_ns = int(max_age_s * 1e9)
        self._seen: OrderedDict[str, int] = OrderedDict()
        self._lock = threading.Lock()

    def verify(self, key: bytes, request: dict[str, Any]) -> str | None:
        """None when ``request`` may be applied, else the reason."""
        sig, nonce = request.get("signature"), request.get("nonce")
        if not isinstance(sig, str) or not isinstance(nonce, str):
            return "the deploy request is not signed by the workbench (no signature or nonce)"
        if not hmac.compare_digest(sig, signature(key, request)):
            return "the deploy request is not signed by the workbench (bad signature)"
        stamp = nonce.partition("-")[0]
        now = time.time_ns()
        if not stamp.isdigit() or abs(now - int(stamp)) > self._max_age_ns:
            return "the deploy request is too old or from the future (nonce time)"
        with self._lock:
            while self._seen and (len(self._seen) >= MAX_NONCES
                                  or next(iter(self._seen.values())) < now - self._max_age_ns):
                self._seen.popitem(last=False)
            if nonce in self._seen:
                return "the deploy request was already applied (replayed nonce)"
            self._seen[nonce] = int(stamp)
        return None
