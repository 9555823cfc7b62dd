"""Exact decimals: periods and planner constants travel as decimal strings and
become `Fraction`s here, never through a float (Fraction(0.3) != 3/10)."""

from __future__ import annotations

import re
from decimal import Decimal, InvalidOperation
from fractions import Fraction

_DECIMAL = re.compile(r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)")

#: Periods are resolved to the microsecond on the link (docs/protocol.md).
MICROS_PER_SECOND = 1_000_000


def is_decimal(text: str) -> bool:
    """True for an unsigned decimal literal such as ``2``, ``2.0``, ``.5``."""
    return _DECIMAL.fullmatch(text) is not None


def canonical_decimal(text: str) -> str:
    """The canonical spelling of a decimal literal: a digit before the point,
    trailing zeros dropped, at least one digit after the point.

    >>> canonical_decimal(".5"), canonical_decimal("2"), canonical_decimal("0.250")
    ('0.5', '2.0', '0.25')
    """
    if not is_decimal(text):
        raise ValueError(f"not a decimal number: {text!r}")
    try:
        d = Decimal(text)
    except InvalidOperation as exc:  # pragma: no cover - the regex already vetted it
        raise ValueError(f"not a decimal number: {text!r}") from exc
    s = format(d.normalize(), "f") if d != 0 else "0"
    if "." not in s:
        s += ".0"
    return s


def to_fraction(text: str) -> Fraction:
    """Exact value of a decimal string.

    >>> to_fraction("0.3")
    Fraction(3, 10)
    """
    if not is_decimal(text):
        raise ValueError(f"not a decimal number: {text!r}")
    return Fraction(text)


def fraction_to_decimal(value: Fraction) -> str:
    """A canonical decimal string for a fraction whose decimal expansion ends
    (denominator of the form 2^a 5^b); raises ValueError otherwise."""
    den = value.denominator
    for p in (2, 5):
        while den % p == 0:
            den //= p
    if den != 1:
        raise ValueError(f"{value} has no finite decimal expansion")
    digits = 0
    while (value * 10**digits).denominator != 1:
        digits += 1
    scaled = value.numerator * 10**digits // value.denominator
    s = str(scaled).rjust(digits + 1, "0")
    text = s[: len(s) - digits] + "." + s[len(s) - digits :] if digits else s
    return canonical_decimal(text)


def to_micros(text: str) -> int:
    """A period in whole microseconds; ValueError if it is finer than that."""
    us = to_fraction(text) * MICROS_PER_SECOND
    if us.denominator != 1:
        raise ValueError(f"{text} s is not a whole number of microseconds")
    return int(us)
