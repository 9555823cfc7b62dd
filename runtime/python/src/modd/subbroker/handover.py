"""One grid across a handover (docs/fleet.md, "The serving station"): the serving station
tells the fleet what the PubBroker runs (config id, epoch, the CONFIG's bytes, the
round trip it was planned for, the model's digest) in its fleet-record answer; a
station that takes the drone over and finds the PubBroker still running that config
(its AUTH_OK's config id and epoch) plans the same model for the same round trip and,
when that gives the very same CONFIG, adopts it instead of sending a new one. The
windows keep their epoch and grid, nothing new crosses the radio, and the handover's
gap is a gap of that one epoch. Anything else (another model, another plan) sends a
new CONFIG, as before.

Over a datagram link the answer also carries the nonces of that station's session (they
cross the air in the handshake, in the clear: the session key needs the drone's link key
as well). What the next station's modem heard while no station served is under that key;
it reads it at takeover and delivers what no station holds (docs/fleet.md, "Diversity
reception").

>>> r = RunningConfig(3, 10**18, b"\\x01\\x02", 0.25, "ab" * 32, 70000, (b"n" * 16, b"s" * 16))
>>> RunningConfig.from_json(r.to_json()) == r
True
>>> RunningConfig.from_json({"config_id": 300})
Traceback (most recent call last):
ValueError: running config: config_id must be an integer in 1..255
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Any

from .kept import model_content

#: A CONFIG larger than this is not told (the link's own bound is far below).
MAX_CONFIG_BYTES = 64 * 1024
#: A handshake nonce longer than this is refused (the link's are 16 bytes).
MAX_NONCE_BYTES = 64


@dataclass(frozen=True)
class RunningConfig:
    """What a serving station's PubBroker runs, as the fleet is told it."""

    config_id: int
    epoch_ns: int
    config: bytes  # the CONFIG frame's body as sent (codec.encode)
    rtt_s: float | None  # the round trip the plan was made for
    model: str  # model_digest of the model it was planned from
    slot: int = 0  # the latest slot that station had (slot numbers travel as 16 bits)
    #: its datagram session's handshake nonces (client's, server's); None over tcp
    session: tuple[bytes, bytes] | None = None

    def to_json(self) -> dict[str, Any]:
        doc: dict[str, Any] = {
            "config_id": self.config_id,
            "epoch_ns": self.epoch_ns,
            "config": self.config.hex(),
            "rtt_s": self.rtt_s,
            "model": self.model,
            "slot": self.slot,
        }
        if self.session is not None:
            doc["session"] = [n.hex() for n in self.session]
        return doc

    @classmethod
    def from_json(cls, doc: Any) -> RunningConfig:
        """From a fleet answer's ``running``; ValueError naming the first bad field."""
        if not isinstance(doc, dict):
            raise ValueError("running config: expected an object")
        cid, epoch = doc.get("config_id"), doc.get("epoch_ns")
        if not isinstance(cid, int) or isinstance(cid, bool) or not 0 < cid < 256:
            raise ValueError("running config: config_id must be an integer in 1..255")
        if not isinstance(epoch, int) or isinstance(epoch, bool) or epoch <= 0:
            raise ValueError("running config: epoch_ns must be a positive integer")
        raw = doc.get("config")
        if not isinstance(raw, str) or len(raw) > 2 * MAX_CONFIG_BYTES:
            raise ValueError(f"running config: config must be hex of at most {MAX_CONFIG_BYTES} B")
        try:
            config = bytes.fromhex(raw)
        except ValueError as exc:
            raise ValueError("running config: config is not hex") from exc
        rtt = doc.get("rtt_s")
        if rtt is not None and (
            not isinstance(rtt, (int, float))
            or isinstance(rtt, bool)
            or not math.isfinite(rtt)
            or not 0 <= rtt < 3600
        ):
            raise ValueError("running config: rtt_s must be null or seconds in [0, 3600)")
        model = doc.get("model")
        if not isinstance(model, str) or len(model) != 64:
            raise ValueError("running config: model must be a SHA-256 digest in hex")
        slot = doc.get("slot", 0)
        if not isinstance(slot, int) or isinstance(slot, bool) or not 0 <= slot < 2**40:
            raise ValueError("running config: slot must be a slot number")
        session = doc.get("session")
        if session is not None:
            if (
                not isinstance(session, list)
                or len(session) != 2
                or not all(isinstance(n, str) and len(n) <= 2 * MAX_NONCE_BYTES for n in session)
            ):
                raise ValueError("running config: session must be two hex nonces")
            try:
                session = (bytes.fromhex(session[0]), bytes.fromhex(session[1]))
            except ValueError as exc:
                raise ValueError("running config: session is not hex") from exc
        rtt_s = None if rtt is None else float(rtt)
        return cls(cid, epoch, config, rtt_s, model, slot, session)


def model_digest(model: dict[str, Any]) -> str:
    """The digest two stations compare: the model's content, layout aside (kept.py)."""
    return hashlib.sha256(model_content(model).encode()).hexdigest()
