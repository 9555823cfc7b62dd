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
from dataclasses import dataclass, field

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


@dataclass(frozen=True)
class Cells:
    """A line taken apart: its columns and ``key=value`` pairs, or its pattern's groups."""

    parts: tuple[str, ...] = ()
    pairs: dict[str, str] = field(default_factory=dict)
    match: re.Match[str] | None = None

    def text(self, where: Where) -> str | None:
        """The text at ``where`` (None: the line has no such column, key or group)."""
        if self.match is not None:
            if isinstance(where, Key):
                return self.match.groupdict().get(where.name)
            return self.match.group(where.number) if where.number <= self.match.re.groups else None
        if isinstance(where, Key):
            return self.pairs.get(where.name)
        return self.parts[where.number - 1] if where.number <= len(self.parts) else None


def cells(fmt: LineFormat, line: str) -> Cells:
    """One line (terminator stripped) taken apart; BadLine when it is too long, not
    printable or does not match the pattern."""
    if len(line) > MAX_LINE:
        raise BadLine(f"line of {len(line)} characters (at most {MAX_LINE})")
    if not line.isprintable():
        raise BadLine("non-printable characters")
    if fmt.pattern is not None:
        m = fmt.pattern.fullmatch(line.strip())
        if m is None:
            raise BadLine("does not match the pattern")
        return Cells(match=m)
    parts = _split(fmt, line.strip())
    pairs = {k.strip(): v for k, sep, v in (p.partition("=") for p in parts) if sep}
    return Cells(tuple(parts), pairs)


def read(c: Cells, wanted: dict[str, Where]) -> dict[str, float]:
    """Every wanted value of a line taken apart, by variable name; BadLine when one lacks."""
    out = {}
    for name, where in wanted.items():
        text = c.text(where)
        if c.match is not None:
            if text is None:
                raise BadLine(f"no group {where} in the match")
            out[name] = _number(text, f"group {where}")
        elif isinstance(where, Column):
            if text is None:
                raise BadLine(f"column {where.number} missing ({len(c.parts)} columns)")
            out[name] = _number(text, f"column {where.number}")
        else:
            if text is None:
                raise BadLine(f"key {where.name!r} missing")
            out[name] = _number(text, f"key {where.name!r}")
    return out


def values(fmt: LineFormat, line: str, wanted: dict[str, Where]) -> dict[str, float]:
    """Every wanted value of one line (terminator stripped), by variable name.
    BadLine when the line is not printable, does not match, or lacks a value:
    a line is taken whole or not at all, so a truncated one archives nothing."""
    return read(cells(fmt, line), wanted)
