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
The bytes are written and read by ``codec.put_number`` and ``codec.get_number``;
this module holds the rule.

>>> steps(1.234, 0.01), steps(0.125, 0.25), steps(1e300, 0.01)
(123, 0, None)
"""

from __future__ import annotations

from modd_contracts.quantised import ESCAPE as ESCAPE  # the wire constants, written once
from modd_contracts.quantised import MAX_DELTA_BITS, MAX_STEPS_BITS
from modd_contracts.quantised import steps as steps  # the rule, written once

#: The largest step count a value may have: exact in a double on both ends.
MAX_STEPS = 1 << MAX_STEPS_BITS
#: The largest delta a decoder accepts (from -2^53 to 2^53).
MAX_DELTA = 1 << MAX_DELTA_BITS
