"""The wire constants of quantised values (declared resolution: docs/protocol.md,
"Quantised values"), written once: ``modd.link.quantise`` reads them, and
``python -m modd_contracts.typegen`` writes them for C++ into
``runtime/cpp/include/modd/link/quantised.gen.hpp``."""

from __future__ import annotations

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
