"""Whether an NMEA sentence carries a measurement: each sentence's own validity
fields decide (NMEA 0183 up to 4.11), never the values (a fix at 0°, 0° is
data; a GGA with fix quality 0 is not, whatever its position says).

=====  ==================================================================
GGA    fix quality (field 6) 0 or empty: no fix
GNS    mode (field 6, one letter per constellation): every letter N: no fix
RMC    status (field 2) not A, or mode (field 12, NMEA 2.3+) N: no fix
GLL    status (field 6) not A, or mode (field 7, NMEA 2.3+) N: no fix
VTG    mode (field 9, NMEA 2.3+) N: no fix
GSA    fix type (field 2) 1 or empty: no fix (its DOPs are not values)
MWV    status (field 5) not A: void
=====  ==================================================================

A sensor's ``fix`` narrows which fixes it accepts (``FIX_CLASSES``): by GGA's
quality and the mode letters of RMC, GLL, VTG and GNS. The default, ``gnss``,
accepts measured fixes (autonomous, differential, precise, RTK); ``any`` also
dead reckoning (GGA 6, mode E); manual input (7, M) and simulation (8, S) are
never a measurement. A narrowed class (``differential``, ``rtk``, ``rtkFixed``)
refuses a sentence that states no class (an NMEA 2.0 RMC without its mode).

Example::

    >>> from modd.sensors.nmea import Sentence
    >>> no_fix(Sentence("GP", "GGA", ("120000", "", "", "", "", "0")), "gnss")
    'GGA fix quality 0 (no fix)'
"""

from __future__ import annotations

from dataclasses import dataclass

from .nmea import Sentence


@dataclass(frozen=True)
class FixClass:
    qualities: frozenset[str]  # GGA field 6
    modes: frozenset[str]  # mode letters of RMC, GLL, VTG, GNS
    narrowed: bool  # a sentence stating no class is refused


def _cls(qualities: str, modes: str, narrowed: bool) -> FixClass:
    return FixClass(frozenset(qualities), frozenset(modes), narrowed)


#: The model's ``fix`` values (docs/sensors.md, "Validity").
FIX_CLASSES = {
    "any": _cls("1234569", "ADPRFE", False),
    "gnss": _cls("123459", "ADPRF", False),
    "differential": _cls("2459", "DPRF", True),
    "rtk": _cls("45", "RF", True),
    "rtkFixed": _cls("4", "R", True),
}
DEFAULT_FIX = "gnss"
_STATUS = {"RMC": 1, "GLL": 5, "MWV": 4}  # 0-based index of the A/V status
_MODE = {"RMC": 11, "GLL": 6, "VTG": 8}  # 0-based index of the mode indicator


def _at(s: Sentence, i: int) -> str | None:
    return s.fields[i] if i < len(s.fields) else None


def _judge(what: str, value: str, says_no_fix: bool, accepted: bool) -> str | None:
    if says_no_fix:
        return f"{what} {value or 'empty'} (no fix)"
    return None if accepted else f"{what} {value} (not accepted by the sensor's fix)"


def _mode(kind: str, mode: str | None, cls: FixClass) -> str | None:
    if not mode:
        return (
            f"{kind} states no mode (the sensor accepts only some fixes)" if cls.narrowed else None
        )
    return _judge(f"{kind} mode", mode, mode == "N", mode in cls.modes)


def _gga(s: Sentence, cls: FixClass) -> str | None:
    q = _at(s, 5) or ""
    return _judge("GGA fix quality", q, q in ("", "0"), q in cls.qualities)


def _gns(s: Sentence, cls: FixClass) -> str | None:
    letters = _at(s, 5) or ""
    no = not letters or set(letters) == {"N"}
    return _judge("GNS mode", letters, no, bool(set(letters) & cls.modes))


def no_fix(s: Sentence, fix: str = DEFAULT_FIX) -> str | None:
    """Why the sentence's values are not measurements, None when they are."""
    cls = FIX_CLASSES[fix]
    if s.type == "GGA":
        return _gga(s, cls)
    if s.type == "GNS":
        return _gns(s, cls)
    if s.type == "GSA":
        return None if _at(s, 1) in ("2", "3") else f"GSA fix type {_at(s, 1) or 'empty'} (no fix)"
    if s.type in _STATUS and (status := _at(s, _STATUS[s.type])) is not None and status != "A":
        return f"{s.type} status {status or 'empty'} (void)"
    if s.type in _MODE:
        return _mode(s.type, _at(s, _MODE[s.type]), cls)
    return None
