"""A variable's unit as CF requires it: a UDUNITS-2 unit string, checked with
UDUNITS-2 itself (the ``cf-units`` wheel bundles the library and its unit
database; imported on first use, ~0.2 s).

A model may write the paper's unit names (``METER_PER_SECOND_SQUARED``: the
schema's ``KnownUnit`` ``x-udunits`` says what each reads as), the symbols
people type (``m/s²``, ``°C``, ``µS/cm``) or a UDUNITS string (``m s-2``).
:func:`udunits` gives the string a dataset writes, in ASCII.

>>> udunits("METER_PER_SECOND_SQUARED"), udunits("m/s²"), udunits("°C")
('m s-2', 'm/s2', 'degC')
>>> unit_problem("furlong per fortnight")
"'furlong per fortnight' is not a UDUNITS-2 unit (e.g. m s-2, degC, degree_north, 1)"
>>> convertible("mS/cm", "S m-1"), convertible("degC", "m")
(True, False)
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from .schema import definition

#: The paper's unit names -> their UDUNITS-2 spelling (the schema's x-udunits).
PAPER_UNITS: dict[str, str] = dict(definition("KnownUnit")["x-udunits"])
#: Words UDUNITS-2 does not know but oceanographers and pilots type: practical
#: salinity is dimensionless in CF (PSU is not a unit), ``deg`` is an angle.
ALIASES = {"PSU": "1", "psu": "1", "deg": "degree", "degrees": "degree"}
#: Typed symbols -> ASCII UDUNITS (superscripts, degree sign, micro, middle dot).
_SYMBOLS = str.maketrans(
    {
        "⁰": "0",
        "¹": "1",
        "²": "2",
        "³": "3",
        "⁴": "4",
        "⁵": "5",
        "⁶": "6",
        "⁷": "7",
        "⁸": "8",
        "⁹": "9",
        "⁻": "-",
        "µ": "u",
        "μ": "u",
        "·": ".",
        "⋅": ".",
        "℃": "degC",
    }
)
EXAMPLES = "m s-2, degC, degree_north, 1"


def _spelled(unit: str) -> str:
    """The unit's UDUNITS spelling before it is parsed."""
    if unit in PAPER_UNITS:
        return PAPER_UNITS[unit]
    text = unit.strip()
    text = ALIASES.get(text, text)
    text = text.replace("°C", "degC").replace("° C", "degC").replace("°", "degree ")
    return " ".join(text.translate(_SYMBOLS).split())


@lru_cache(maxsize=4096)
def _parse(text: str) -> Any:
    """The cf_units Unit of ``text``; ValueError when UDUNITS-2 cannot read it."""
    import cf_units

    return cf_units.Unit(text)


@lru_cache(maxsize=4096)
def unit_problem(unit: str) -> str | None:
    """Why ``unit`` is not a unit a dataset can declare, or None."""
    if unit in PAPER_UNITS:
        return None  # UDUNITS-2 spellings held by a test: no need to load UDUNITS (numpy)
    try:
        _parse(_spelled(unit))
    except ValueError:
        return f"{unit!r} is not a UDUNITS-2 unit (e.g. {EXAMPLES})"
    return None


def udunits(unit: str) -> str:
    """The ASCII UDUNITS-2 string of a model's unit (ValueError when it is none)."""
    text = _spelled(unit)
    _parse(text)
    return text


def convertible(unit: str, to: str) -> bool:
    """True when values in ``unit`` convert to ``to`` (both model or UDUNITS units)."""
    try:
        return bool(_parse(_spelled(unit)).is_convertible(_parse(_spelled(to))))
    except ValueError:
        return False
