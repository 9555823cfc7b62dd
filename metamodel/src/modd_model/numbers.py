"""Exact decimals: periods and planner constants travel as decimal strings and
become `Fraction`s here, never through a float (Fraction(0.3) != 3/10)."""

from __future__ import annotations

import re
from decimal import Decimal, InvalidOperation
from fractions import Fraction

_DECIMAL = re.compile(r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)")
# What the text form accepts: a decimal literal, optionally with an exponent
# (4.0E-2, as Xtext's EDouble writes it); used with fullmatch (no trailing newline).
_LITERAL = re.compile(r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
#: Longest canonical decimal accepted: bounds what an exponent can blow up to.
MAX_DECIMAL_CHARS = 40

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
    >>> canonical_decimal("4.0E-2")
    '0.04'
    """
    if not _LITERAL.match(text):
        raise ValueError(f"not a decimal number: {text!r}")
    try:
        d = Decimal(text)
    except InvalidOperation as exc:  # pragma: no cover - the regex already vetted it
        raise ValueError(f"not a decimal number: {text!r}") from exc
    # Decide on the exponent before formatting: 1e999999999 must not be expanded.
    if d != 0 and not -MAX_DECIMAL_CHARS < d.adjusted() < MAX_DECIMAL_CHARS:
        raise ValueError(f"number {text} is out of range")
    s = format(d.normalize(), "f") if d != 0 else "0"
    if len(s) > MAX_DECIMAL_CHARS:
        raise ValueError(f"number {text} has more than {MAX_DECIMAL_CHARS} digits")
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
