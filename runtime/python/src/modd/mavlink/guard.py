"""What the bridge accepts from the MAVLink link (docs/security.md, "MAVLink"):
a rate bound per message and, when a signing key is given, MAVLink 2 signing.

Any local process can send UDP datagrams to the bridge's port; the bridge
maps only messages from the autopilot's system and component (Autopilot),
at most ``RATE_FACTOR`` times the rate it asked for each message (after a
burst of BURST_S seconds' worth, what a radio or UART buffer releases at
once), and, with a key, only frames signed with it.

>>> bound = RateBound({"ATTITUDE": 100_000})       # asked every 0.1 s: 20/s allowed
>>> sum(bound.allow("ATTITUDE", t / 1000) for t in range(1000))  # 1 kHz for 1 s: 40 + 20
59
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

#: Messages beyond this multiple of the asked rate (after a burst) are dropped.
RATE_FACTOR = 2.0
BURST_S = 2.0
#: Messages the model does not map (HEARTBEAT, COMMAND_ACK...) get this rate.
OTHER_RATE_HZ = 20.0


class RateBound:
    """A token bucket per message name."""

    def __init__(self, intervals_us: dict[str, int]) -> None:
        self._rate = {m: RATE_FACTOR * 1e6 / max(i, 1) for m, i in intervals_us.items()}
        self._tokens: dict[str, float] = {}
        self._at: dict[str, float] = {}

    def burst(self, message: str) -> float:
        """Messages let through at once (at least 10)."""
        return max(10.0, BURST_S * self._rate.get(message, OTHER_RATE_HZ))

    def allow(self, message: str, now: float) -> bool:
        rate = self._rate.get(message, OTHER_RATE_HZ)
        burst = self.burst(message)
        last = self._at.get(message)
        tokens = self._tokens.get(message, burst)
        if last is not None:
            tokens = min(burst, tokens + (now - last) * rate)
        self._at[message] = now
        if tokens < 1.0:
            self._tokens[message] = tokens
            return False
        self._tokens[message] = tokens - 1.0
        return True


def signing_key(ref: str) -> bytes:
    """The 32-byte MAVLink 2 signing secret from ``file:PATH`` (SHA-256 of the
    file's text, as MAVProxy's ``signing setup PASSPHRASE`` derives it)."""
    from ..zenoh_auth import read_secret

    kind, _, name = ref.partition(":")
    if kind != "file" or not name:
        raise ValueError(f"signing key {ref!r}: expected file:PATH")
    return hashlib.sha256(read_secret(Path(name), "MAVLink signing key")).digest()


def require_signing(mav: Any, key: bytes) -> None:
    """Make a pymavlink parser accept only frames signed with ``key``
    (unsigned or wrongly signed frames decode as BAD_DATA)."""
    mav.signing.secret_key = key
    mav.signing.sign_outgoing = True
    mav.signing.allow_unsigned_callback = lambda _mav, _msgid: False
