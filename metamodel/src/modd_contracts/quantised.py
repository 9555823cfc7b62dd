"""The wire constants of quantised values (declared resolution: docs/protocol.md,
"Quantised values"), written once: ``modd.link.quantise`` reads them, and
``python -m modd_contracts.typegen`` writes them for C++ into
``runtime/cpp/include/modd/link/quantised.gen.hpp``; and the rule that turns a
value into steps, :func:`steps`, which the Python codec and the planner's
calibration (``modd_plan.calibration``) share.

>>> steps(1.234, 0.01), steps(0.125, 0.25), steps(1e300, 0.01)
(123, 0, None)
"""

from __future__ import annotations

import math

#: The code of a value sent exactly (f64le follows) instead of as steps.
ESCAPE = 0
#: A value's step count is at most 2^MAX_STEPS_BITS in magnitude (exact in a double).
MAX_STEPS_BITS = 53
#: A delta between two step counts is at most 2^MAX_DELTA_BITS in magnitude.
MAX_DELTA_BITS = 54

CONSTANTS: tuple[tuple[str, int, str], ...] = (
    ("ESCAPE", ESCAPE, "The code of a value sent exactly (f64le follows) instead of as steps."),
    ("MAX_STEPS_BITS", MAX_STEPS_BITS, "A step count is at most 2^this in magnitude."),
    ("MAX_DELTA_BITS", MAX_DELTA_BITS, "A delta of step counts is at most 2^this in magnitude."),
)


def steps(x: float, resolution: float) -> int | None:
    """``round(x / r)`` (half to even, as C's nearbyint) when ``q * r`` restores
    ``x`` within half a step, else None (sent unquantised: the escape)."""
    if not math.isfinite(x):
        return None
    ratio = x / resolution
    limit = 1 << MAX_STEPS_BITS
    if not math.isfinite(ratio) or abs(ratio) > limit:
        return None
    q = round(ratio)
    if abs(q) > limit or abs(q * resolution - x) > resolution / 2:
        return None
    return q
