"""ASCII line instruments (CTDs, sondes, fluorometers): one line per sample,
columns split by a separator, ``key=value`` pairs, or the named groups of a
regular expression the model gives.

Example::

    >>> fmt = LineFormat(separator=",")
    >>> values(fmt, "12.31, 45.02 ,1013", {"t": Column(1), "c": Column(2)})
    {'t': 12.31, 'c': 45.02}
    >>> values(LineFormat(separator=" "), "T=12.3 C=45.1", {"c": Key("C")})
    {'c': 45.1}
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

MAX_LINE = 4096


class BadLine(ValueError):
    """A line that does not have the form the model declares; the message says why."""


@dataclass(frozen=True)
class Column:
    number: int  # 1-based


@dataclass(frozen=True)
class Key:
    name: str


Where = Column | Key


@dataclass(frozen=True)
class LineFormat:
    separator: str = ","  # " ": any run of spaces or tabs
    pattern: re.Pattern[str] | None = None  # a line must match; keys are its named groups


def _number(text: str, what: str) -> float:
    try:
        value = float(text.strip())
    except ValueError:
        raise BadLine(f"{what} {text.strip()[:40]!r} is not a number") from None
    if not math.isfinite(value):
        raise BadLine(f"{what} {text.strip()[:40]!r} is not finite")
    return value


def _split(fmt: LineFormat, line: str) -> list[str]:
    return line.split() if fmt.separator == " " else line.split(fmt.separator)


def values(fmt: LineFormat, line: str, wanted: dict[str, Where]) -> dict[str, float]:
    """Every wanted value of one line (terminator stripped), by variable name.
    BadLine when the line is not printable, does not match, or lacks a value:
    a line is taken whole or not at all, so a truncated one archives nothing."""
    if len(line) > MAX_LINE:
        raise BadLine(f"line of {len(line)} characters (at most {MAX_LINE})")
    if not line.isprintable():
        raise BadLine("non-printable characters")
    if fmt.pattern is not None:
        m = fmt.pattern.fullmatch(line.strip())
        if m is None:
            raise BadLine("does not match the pattern")
        groups = m.groupdict()
        out = {}
        for name, where in wanted.items():
            text = (
                groups.get(where.name)
                if isinstance(where, Key)
                else (m.group(where.number) if where.number <= (m.re.groups or 0) else None)
            )
            if text is None:
                raise BadLine(f"no group {where} in the match")
            out[name] = _number(text, f"group {where}")
        return out
    parts = _split(fmt, line.strip())
    pairs = {k.strip(): v for k, sep, v in (p.partition("=") for p in parts) if sep}
    out = {}
    for name, where in wanted.items():
        if isinstance(where, Column):
            if where.number > len(parts):
                raise BadLine(f"column {where.number} missing ({len(parts)} columns)")
            out[name] = _number(parts[where.number - 1], f"column {where.number}")
        else:
            if where.name not in pairs:
                raise BadLine(f"key {where.name!r} missing")
            out[name] = _number(pairs[where.name], f"key {where.name!r}")
    return out
