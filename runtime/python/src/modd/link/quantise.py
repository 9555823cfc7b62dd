"""Declared resolution on the live link (docs/protocol.md, "Quantised values").

A stream whose CONFIG declares a resolution ``r`` carries each of its float
values (the value, AVERAGE's mean, each ALL element) as an integer number of
steps ``q = round(x / r)``, delta-coded against the same stream's previous
value in the same unit (one DATA frame, one DATA datagram, one fragmented
slot), as ``varint(zigzag(delta) + 1)``; the first value of a stream in a unit
is its absolute step count. Code 0 is the escape: the value follows as f64le
(exact: the broker aggregates in double) whenever the steps would not restore it
within half a step (not finite, beyond 2^53 steps), so the error bound holds for
every value. A unit decodes on its own: a lost datagram never corrupts another.

>>> chain: dict[int, int] = {}
>>> b = bytearray()
>>> put_number(b, chain, 0, 1.234, 0.01); put_number(b, chain, 0, 1.25, 0.01)
>>> bytes(b).hex()
'f70105'
>>> r = Reader(bytes(b)); back: dict[int, int] = {}
>>> [round(get_number(r, back, 0, 0.01), 6) for _ in range(2)]
[1.23, 1.25]
"""

from __future__ import annotations

import math
import struct

from .codec import Reader, unzigzag, varint, zigzag

#: The largest step count a value may have: exact in a double on both ends.
MAX_STEPS = 1 << 53
#: The largest delta a decoder accepts (twice MAX_STEPS: from -2^53 to 2^53).
MAX_DELTA = 1 << 54
ESCAPE = 0


def steps(x: float, resolution: float) -> int | None:
    """``round(x / r)`` (half to even, as C's nearbyint) when ``q * r`` restores
    ``x`` within half a step, else None (sent unquantised)."""
    if not math.isfinite(x):
        return None
    ratio = x / resolution
    if not math.isfinite(ratio) or abs(ratio) > MAX_STEPS:
        return None
    q = round(ratio)
    if abs(q) > MAX_STEPS or abs(q * resolution - x) > resolution / 2:
        return None
    return q


def put_number(b: bytearray, chain: dict[int, int], key: int, x: float, resolution: float) -> None:
    """One quantised value of stream ``key`` (its step count joins the chain)."""
    q = steps(x, resolution)
    if q is None:
        b += varint(ESCAPE) + struct.pack("<d", x)
        return
    prev = chain.get(key)
    b += varint(zigzag(q - prev if prev is not None else q) + 1)
    chain[key] = q


def get_number(r: Reader, chain: dict[int, int], key: int, resolution: float) -> float:
    code = r.varint()
    if code == ESCAPE:
        return float(r.fixed("<d"))
    delta = unzigzag(code - 1)
    if abs(delta) > MAX_DELTA:
        raise r.fail(f"quantised delta {delta} beyond 2^54 steps")
    prev = chain.get(key)
    q = prev + delta if prev is not None else delta
    if abs(q) > MAX_STEPS:
        raise r.fail(f"quantised value of {q} steps beyond 2^53")
    chain[key] = q
    return q * resolution
