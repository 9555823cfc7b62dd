"""A source's condition (the model's ``where``): a variable is read only from
the sentences or lines where another of their fields compares so. MWV's
reference (``T`` true, ``R`` relative wind) splits one sentence type into two
topics; an XDR transducer's name picks its quadruplet; a CTD line's record
type picks the lines a column is read from. Pure functions, no I/O.

``=`` and ``!=`` compare text exactly, except a field the sentence table says
holds a number (or a position), compared as a number; ``<``, ``<=``, ``>``,
``>=`` compare numbers. An empty or absent field meets no condition (``!=``
neither): it holds nothing to compare.

Example::

    >>> from modd.sensors.nmea import parse_sentence
    >>> s = parse_sentence("$WIMWV,57.5,T,4.2,N,A*14")
    >>> nmea_field(s, "angle", Condition("reference", "=", "T"))
    'angle'
    >>> nmea_field(s, "angle", Condition("reference", "=", "R")) is None
    True
    >>> x = parse_sentence("$IIXDR,C,12.5,C,AIRTEMP,P,1.013,B,BARO*21")
    >>> nmea_field(x, "value", Condition("id", "=", "BARO"))
    'f6'
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass

from modd_model.vocabulary import NMEA_SENTENCES

from .ascii import Cells, Where
from .nmea import NoValue, Sentence, field_value, position

_ORDER: dict[str, Callable[[float, float], bool]] = {
    "=": operator.eq,
    "!=": operator.ne,
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
}
_XDR = list(NMEA_SENTENCES["XDR"])  # type, value, unit, id: one quadruplet


@dataclass(frozen=True)
class Condition:
    place: str | Where  # nmea: a field name or fN; ascii: a Column or a Key
    op: str  # = != < <= > >=
    value: str  # as the model writes it


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _numbers(a: float | None, op: str, value: str) -> bool:
    b = _number(value)
    return a is not None and b is not None and _ORDER[op](a, b)


def compare(text: str, op: str, value: str, numeric: bool) -> bool:
    """Whether ``text op value`` holds (as numbers when ``numeric``, else as text)."""
    if not numeric:
        return text == value if op == "=" else text != value if op == "!=" else False
    return _numbers(_number(text), op, value)


def _holds(s: Sentence, field: str, cond: Condition) -> bool:
    i, kind = position(s.type, field)
    if i >= len(s.fields) or not s.fields[i]:
        return False
    if kind in ("number", "latitude", "longitude"):
        try:
            return _numbers(field_value(s, field), cond.op, cond.value)
        except NoValue:
            return False
    return compare(s.fields[i], cond.op, cond.value, cond.op not in ("=", "!="))


def nmea_field(s: Sentence, field: str, cond: Condition | None) -> str | None:
    """The field to read from ``s`` for a source reading ``field`` under ``cond``:
    ``field`` itself, or, for XDR with a condition on the quadruplet's type, value,
    unit or id, the ``fN`` of ``field`` in the first quadruplet meeting it; None when
    the sentence does not meet the condition."""
    if cond is None:
        return field
    assert isinstance(cond.place, str)
    if s.type == "XDR" and cond.place in _XDR and field in _XDR:
        at, read = _XDR.index(cond.place), _XDR.index(field)
        for group in range(0, len(s.fields), len(_XDR)):
            if _holds(s, f"f{group + at + 1}", cond):
                return f"f{group + read + 1}"
        return None
    return field if _holds(s, cond.place, cond) else None


def ascii_holds(c: Cells, cond: Condition | None) -> bool:
    """Whether a line taken apart meets ``cond`` (no condition: always)."""
    if cond is None:
        return True
    assert not isinstance(cond.place, str)
    text = c.text(cond.place)
    return text is not None and compare(
        text.strip(), cond.op, cond.value, cond.op not in ("=", "!=")
    )
