"""NMEA 0183 sentences → field values, talker-agnostic (``$GPGGA`` and
``$GNGGA`` are both ``GGA``), with the checks a reader needs before it trusts
a line: the ``$``/``!`` start, printable ASCII only, the ``*hh`` checksum
(required unless the sensor says ``checksum = optional``: then a line without
one must have the exact shape of its sentence, field by field), and a bounded
length. A sentence may carry more fields than the table (NMEA 4.x system ids,
vendor variants, a trailing empty field): its checksum vouches for them and
the extra fields are kept, unread. An address that is not talker + type
(``$PUBX``, ``$LOG…``) is a well-formed line the model cannot map (counted
ignored by the decoder, not bad). The field tables are the metamodel's
(``modd_model.vocabulary.NMEA_SENTENCES``), read from the schema.

Example::

    >>> s = parse_sentence("$GPDBT,12.3,f,3.75,M,2.05,F*30")
    >>> s.type, s.talker, field_value(s, "depth_meters")
    ('DBT', 'GP', 3.75)
"""

from __future__ import annotations

import calendar
import re
from dataclasses import dataclass

from modd_model.vocabulary import NMEA_SENTENCES

MAX_LINE = 512  # the standard's 82; vendors' long proprietary lines still pass, memory bounded
MAX_BARE = 120  # a line without a checksum: the standard's 82, with slack
_ADDRESS = re.compile(r"[A-Z0-9]{2,16}")
_HEX = frozenset("0123456789ABCDEFabcdef")
# What a field of each kind may hold in a line without a checksum (empty: no value).
_SHAPES = {
    "number": re.compile(r"[-+]?[0-9]*\.?[0-9]*"),
    "latitude": re.compile(r"(?:[0-9]{4}(?:\.[0-9]*)?)?"),
    "longitude": re.compile(r"(?:[0-9]{5}(?:\.[0-9]*)?)?"),
    "time": re.compile(r"(?:[0-9]{6}(?:\.[0-9]*)?)?"),
    "date": re.compile(r"(?:[0-9]{6})?"),
    "status": re.compile(r"[AV]?"),
    "text": re.compile(r"[^,*$!]*"),
}


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


def parse_sentence(line: str, checksum_required: bool = True) -> Sentence:
    """One line (terminator stripped) → its sentence; BadSentence says why not.
    With ``checksum_required=False`` a line without ``*hh`` is read when its
    shape is exactly its sentence's (a line with one is still checked)."""
    if len(line) > MAX_LINE:
        raise BadSentence(f"line of {len(line)} characters (at most {MAX_LINE})")
    if not line or line[0] not in "$!":
        raise BadSentence("does not start with $ or !")
    if not line.isascii() or not line.isprintable():
        raise BadSentence("non-printable or non-ASCII characters")
    body, star, given = line[1:].rpartition("*")
    if star:
        if len(given) != 2 or not set(given) <= _HEX:
            raise BadSentence(f"checksum {given!r} is not two hex digits")
        if int(given, 16) != checksum(body):
            raise BadSentence(f"bad checksum {given.upper()} (computed {checksum(body):02X})")
    elif checksum_required:
        raise BadSentence("no *hh checksum (truncated?)")
    else:
        body = line[1:]
    if "$" in body or "!" in body[1:] or "*" in body:
        raise BadSentence("two sentences run together")
    s = _address(body.split(","))
    if s.type == "XDR" and len(s.fields) % 4:
        raise BadSentence(f"XDR with {len(s.fields)} fields (groups of 4)")
    if not star:
        _bare_shape(s, len(line))
    return s


def _address(parts: list[str]) -> Sentence:
    address, *fields = parts
    if address.startswith("P"):  # proprietary: the vendor's own address (may hold spaces)
        return Sentence("P", address[1:], tuple(fields))
    if len(address) == 5 and _ADDRESS.fullmatch(address):
        return Sentence(address[:2], address[2:], tuple(fields))
    if not _ADDRESS.fullmatch(address):
        raise BadSentence(f"address {address!r} is not talker + sentence type")
    return Sentence("", address, tuple(fields))  # $LOG..., vendors' own: never mapped


def _bare_shape(s: Sentence, length: int) -> None:
    """The stricter checks of a line without a checksum: a known sentence, at most
    its fields, each of its kind's shape (so a cut or merged line is refused)."""
    if length > MAX_BARE:
        raise BadSentence(f"line of {length} characters without checksum (at most {MAX_BARE})")
    table = NMEA_SENTENCES.get(s.type)
    if table is None or s.talker in ("", "P"):
        return  # unmapped anyway: read as well-formed, counted ignored
    kinds = list(table.values())
    if s.type != "XDR" and len(s.fields) > len(kinds):
        raise BadSentence(
            f"{s.type} with {len(s.fields)} fields and no checksum (at most {len(kinds)})"
        )
    for i, text in enumerate(s.fields):
        kind = kinds[i % len(kinds)]
        if not _SHAPES[kind].fullmatch(text):
            raise BadSentence(f"{s.type} field {i + 1} {text!r} is not a {kind} (no checksum)")


class NoValue(ValueError):
    """A field that carries no value in this sentence (empty, absent, or not a number)."""


def position(kind: str, field: str) -> tuple[int, str]:
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
    i, kind = position(s.type, field)
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


def _hms(text: str) -> float:
    """hhmmss[.ss] → seconds of the day; NoValue when it is not a time."""
    if len(text) < 6 or not text[:6].isdigit():
        raise NoValue(f"time {text!r}")
    h, m, sec = int(text[:2]), int(text[2:4]), float(text[4:])
    if h > 23 or m > 59 or sec >= 61:
        raise NoValue(f"time {text!r}")
    return h * 3600 + m * 60 + sec


def time_of_day(s: Sentence) -> float | None:
    """The UTC time of day (seconds) the sentence states in its time field, None
    when it has none (a sentence type without one, or an empty or bad field)."""
    table = NMEA_SENTENCES.get(s.type)
    if table is None or "time" not in table:
        return None
    i = list(table).index("time")
    try:
        return _hms(s.fields[i]) if i < len(s.fields) else None
    except (NoValue, ValueError):
        return None


def stated_date(s: Sentence) -> tuple[int, int, int, bool] | None:
    """(year, month, day, two_digit_year) of an RMC's or ZDA's date; None without one."""
    f = s.fields
    try:
        if s.type == "ZDA" and len(f) >= 4 and all(f[1:4]):
            day, month, year, short = int(f[1]), int(f[2]), int(f[3]), False
        elif s.type == "RMC" and len(f) >= 9 and len(f[8]) == 6 and f[8].isdigit():
            day, month, year, short = int(f[8][:2]), int(f[8][2:4]), int(f[8][4:]), True
        else:
            return None
    except ValueError:
        return None
    if not (1 <= month <= 12 and 1 <= day <= 31 and 0 <= year <= 9999):
        return None
    return year, month, day, short


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
