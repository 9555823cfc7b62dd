"""NMEA 0183 sentences → field values, talker-agnostic (``$GPGGA`` and
``$GNGGA`` are both ``GGA``), with the checks a reader needs before it trusts
a line: the ``$``/``!`` start, the ``*hh`` checksum (required: a line without
one is refused, which is how a truncated line shows), printable ASCII only,
at most 82 characters as the standard says (a little slack for receivers that
exceed it), and no more fields than the sentence has (a merged line fails
the checksum or this). The field tables are the metamodel's
(``modd_model.vocabulary.NMEA_SENTENCES``), read from the schema.

Example::

    >>> s = parse_sentence("$GPDBT,12.3,f,3.75,M,2.05,F*30")
    >>> s.type, s.talker, field_value(s, "depth_meters")
    ('DBT', 'GP', 3.75)
"""

from __future__ import annotations

import calendar
from dataclasses import dataclass

from modd_model.vocabulary import NMEA_SENTENCES

MAX_LINE = 120  # the standard's 82, with slack for receivers that exceed it


class BadSentence(ValueError):
    """A line that is not a well-formed NMEA sentence; the message says why."""


@dataclass(frozen=True)
class Sentence:
    talker: str  # GP, GN, GL, II, ... ("P" for a proprietary sentence)
    type: str  # GGA, RMC, ... (talker-agnostic)
    fields: tuple[str, ...]  # the fields after the address, field 1 first


def checksum(body: str) -> int:
    """XOR of the characters between ``$`` and ``*``."""
    out = 0
    for c in body.encode("ascii"):
        out ^= c
    return out


def sentence(talker: str, kind: str, fields: list[str]) -> str:
    """The line (with its checksum, without terminator) that ``parse_sentence`` reads back.

    >>> sentence("II", "MTW", ["12.5", "C"])
    '$IIMTW,12.5,C*15'
    """
    body = ",".join([talker + kind, *fields])
    return f"${body}*{checksum(body):02X}"


def parse_sentence(line: str) -> Sentence:
    """One line (terminator stripped) → its sentence; BadSentence says why not."""
    if len(line) > MAX_LINE:
        raise BadSentence(f"line of {len(line)} characters (at most {MAX_LINE})")
    if not line or line[0] not in "$!":
        raise BadSentence("does not start with $ or !")
    if not line.isascii() or not line.isprintable():
        raise BadSentence("non-printable or non-ASCII characters")
    body, star, given = line[1:].rpartition("*")
    if not star:
        raise BadSentence("no *hh checksum (truncated?)")
    if len(given) != 2 or not all(c in "0123456789ABCDEFabcdef" for c in given):
        raise BadSentence(f"checksum {given!r} is not two hex digits")
    if int(given, 16) != checksum(body):
        raise BadSentence(f"bad checksum {given.upper()} (computed {checksum(body):02X})")
    if "$" in body or "*" in body:
        raise BadSentence("two sentences run together")
    address, *fields = body.split(",")
    if address.startswith("P"):
        talker, kind = "P", address[1:]
    elif len(address) == 5 and address.isalnum():
        talker, kind = address[:2], address[2:]
    else:
        raise BadSentence(f"address {address!r} is not talker + sentence type")
    known = NMEA_SENTENCES.get(kind)
    if known is not None and kind != "XDR" and len(fields) > len(known):
        raise BadSentence(f"{kind} with {len(fields)} fields (at most {len(known)})")
    if kind == "XDR" and len(fields) % 4:
        raise BadSentence(f"XDR with {len(fields)} fields (groups of 4)")
    return Sentence(talker, kind, tuple(fields))


class NoValue(ValueError):
    """A field that carries no value in this sentence (empty, absent, or not a number)."""


def _position(kind: str, field: str) -> tuple[int, str]:
    """(0-based index, field kind) of a field named in the table or written ``fN``."""
    table = NMEA_SENTENCES[kind]
    names = list(table)
    if field in table:
        return names.index(field), table[field]
    n = int(field[1:]) - 1
    kinds = list(table.values())
    return n, kinds[n % len(kinds)] if kind == "XDR" else kinds[n] if n < len(kinds) else "number"


def _coordinate(text: str, hemisphere: str, degree_digits: int) -> float:
    """ddmm.mmmm (latitude) or dddmm.mmmm (longitude) with N/S/E/W → signed degrees."""
    if hemisphere not in ("NS" if degree_digits == 2 else "EW") or len(text) < degree_digits + 2:
        raise NoValue(f"coordinate {text!r} {hemisphere!r}")
    degrees, minutes = int(text[:degree_digits]), float(text[degree_digits:])
    if minutes >= 60:
        raise NoValue(f"minutes {minutes} in {text!r}")
    value = degrees + minutes / 60
    return -value if hemisphere in "SW" else value


def field_value(s: Sentence, field: str) -> float:
    """The number a mapped field carries (latitude/longitude in signed decimal
    degrees); NoValue when the field is empty, absent or not a number."""
    i, kind = _position(s.type, field)
    if i >= len(s.fields) or not s.fields[i]:
        raise NoValue(f"{s.type} field {i + 1} is empty")
    text = s.fields[i]
    try:
        if kind == "latitude":
            return _coordinate(text, s.fields[i + 1] if i + 1 < len(s.fields) else "", 2)
        if kind == "longitude":
            return _coordinate(text, s.fields[i + 1] if i + 1 < len(s.fields) else "", 3)
        value = float(text)
    except ValueError as exc:
        raise NoValue(f"{s.type} field {i + 1} {text!r} is not a number") from exc
    if value != value or value in (float("inf"), float("-inf")):
        raise NoValue(f"{s.type} field {i + 1} {text!r} is not finite")
    return value


def void(s: Sentence) -> bool:
    """True when the sentence says its data is not valid (RMC/GLL status V, MWV V)."""
    table = NMEA_SENTENCES.get(s.type, {})
    for i, kind in enumerate(table.values()):
        if kind == "status" and i < len(s.fields):
            return s.fields[i] != "A"
    return False


def _hms(text: str) -> float:
    if len(text) < 6 or not text[:6].isdigit():
        raise NoValue(f"time {text!r}")
    h, m, sec = int(text[:2]), int(text[2:4]), float(text[4:])
    if h > 23 or m > 59 or sec >= 61:
        raise NoValue(f"time {text!r}")
    return h * 3600 + m * 60 + sec


def instrument_time_ns(s: Sentence) -> int | None:
    """The UTC time a ZDA or RMC sentence states (ns since the Unix epoch); None
    for other sentences or when it states none."""
    try:
        if s.type == "ZDA" and len(s.fields) >= 4 and all(s.fields[:4]):
            day, month, year = (int(x) for x in s.fields[1:4])
        elif s.type == "RMC" and len(s.fields) >= 9 and s.fields[0] and len(s.fields[8]) == 6:
            d = s.fields[8]
            day, month, year = int(d[:2]), int(d[2:4]), 2000 + int(d[4:6])
        else:
            return None
        seconds = _hms(s.fields[0])
        midnight = calendar.timegm((year, month, day, 0, 0, 0))
        if not (1 <= month <= 12 and 1 <= day <= 31):
            return None
    except (NoValue, ValueError, OverflowError):
        return None
    return midnight * 1_000_000_000 + round(seconds * 1e9)
