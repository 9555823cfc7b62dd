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
    if not _LITERAL.fullmatch(text):  # the whole text: no trailing newline or blank
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
    """The canonical decimal string of a fraction whose decimal expansion ends
    (denominator of the form 2^a 5^b); raises ValueError otherwise.

    Exact whatever its length: this writes computed values (a plan's
    hyperperiod can have hundreds of digits, bounded by the planner), unlike
    :func:`canonical_decimal`, which bounds what a text may ask for.

    >>> fraction_to_decimal(Fraction(3, 8)), fraction_to_decimal(Fraction(-5))
    ('0.375', '-5.0')
    """
    num, den = value.numerator, value.denominator
    twos = fives = 0
    while den % 2 == 0:
        den //= 2
        twos += 1
    while den % 5 == 0:
        den //= 5
        fives += 1
    if den != 1:
        raise ValueError(f"{value} has no finite decimal expansion")
    digits = max(twos, fives)  # value * 10^digits is a whole number
    scaled = abs(num) * 10**digits // value.denominator
    whole, frac = divmod(scaled, 10**digits)
    fraction = str(frac).rjust(digits, "0").rstrip("0") if digits else ""
    return f"{'-' if num < 0 else ''}{whole}.{fraction or '0'}"


def to_micros(text: str) -> int:
    """A period in whole microseconds; ValueError if it is finer than that."""
    us = to_fraction(text) * MICROS_PER_SECOND
    if us.denominator != 1:
        raise ValueError(f"{text} s is not a whole number of microseconds")
    return int(us)
