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

A SubBroker keeps the nonces it accepted in a file (``NonceGuard(path=...)``),
so a signed deploy replayed after a restart is refused too.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import re
import secrets
import threading
import time
from collections import OrderedDict
from pathlib import Path
from typing import Any

#: How old (or how far in the future) a signed request may be.
MAX_AGE_S = 300.0
#: Nonces remembered (a request older than MAX_AGE_S is refused anyway).
MAX_NONCES = 100_000
DOMAIN = b"modd-deploy-v1\n"
#: What ``sign_request`` makes: issue time in ns, "-", 128 random bits in hex.
NONCE = re.compile(r"[0-9]{1,20}-[0-9a-f]{32}")


def _message(request: dict[str, Any]) -> bytes:
    body = {k: v for k, v in request.items() if k != "signature"}
    return (
        DOMAIN + json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode()
    )


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
    of the time window. Thread-safe; memory bounded by MAX_NONCES.

    With ``path``, every accepted nonce is appended to that file (0600,
    synced) before the request is applied, and the file is read back at
    start: a replay is refused across restarts too. The file holds only
    nonces still inside the window (rewritten when half of it has expired).
    A nonce that cannot be recorded refuses the request."""

    def __init__(self, max_age_s: float = MAX_AGE_S, path: str | Path | None = None) -> None:
        self._max_age_ns = int(max_age_s * 1e9)
        self._seen: OrderedDict[str, int] = OrderedDict()
        self._lock = threading.Lock()
        self._path = Path(path) if path is not None else None
        self._lines = 0
        if self._path is not None:
            self._load(self._path)

    def _load(self, path: Path) -> None:
        try:
            with path.open("rb") as f:
                f.seek(max(0, os.fstat(f.fileno()).st_size - MAX_NONCES * 56))
                lines = f.read().decode("ascii", "replace").splitlines()
        except FileNotFoundError:
            lines = []
        now = time.time_ns()
        for nonce in lines:
            if NONCE.fullmatch(nonce):
                stamp = int(nonce.partition("-")[0])
                if abs(now - stamp) <= self._max_age_ns:
                    self._seen[nonce] = stamp
        self._rewrite()

    def _rewrite(self) -> None:
        assert self._path is not None
        tmp = self._path.with_name(f"{self._path.name}.{os.getpid()}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write("".join(n + "\n" for n in self._seen))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self._path)
        self._lines = len(self._seen)

    def _record(self, nonce: str) -> None:
        assert self._path is not None
        fd = os.open(self._path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o600)
        try:
            os.write(fd, (nonce + "\n").encode("ascii"))
            os.fsync(fd)
        finally:
            os.close(fd)
        self._lines += 1
        if self._lines > 2 * len(self._seen) + 64:
            self._rewrite()

    def verify(self, key: bytes, request: dict[str, Any]) -> str | None:
        """None when ``request`` may be applied, else the reason."""
        sig, nonce = request.get("signature"), request.get("nonce")
        if not isinstance(sig, str) or not isinstance(nonce, str):
            return "the deploy request is not signed by the workbench (no signature or nonce)"
        if not hmac.compare_digest(sig, signature(key, request)):
            return "the deploy request is not signed by the workbench (bad signature)"
        if not NONCE.fullmatch(nonce):
            return "the deploy request's nonce is malformed"
        stamp = int(nonce.partition("-")[0])
        now = time.time_ns()
        if abs(now - stamp) > self._max_age_ns:
            return "the deploy request is too old or from the future (nonce time)"
        with self._lock:
            while self._seen and next(iter(self._seen.values())) < now - self._max_age_ns:
                self._seen.popitem(last=False)
            if nonce in self._seen:
                return "the deploy request was already applied (replayed nonce)"
            if len(self._seen) >= MAX_NONCES:
                # evicting a live nonce would let it be replayed: refuse instead
                return "too many deploys within the nonce window; retry later"
            if self._path is not None:
                try:
                    self._record(nonce)
                except OSError as exc:
                    return f"the deploy request's nonce cannot be recorded ({exc.strerror})"
            self._seen[nonce] = stamp
        return None
