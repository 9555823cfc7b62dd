"""A small TOML writer for the generated configs (the SubBroker's
subbroker.toml): values are serialised, never templated, so that no model
string can end a string, start a table or add a key. Covers what the configs
use: tables, strings, booleans, integers, finite floats and arrays of those.

>>> print(dumps({"drone": "usv", "zenoh": {"listen": ["tcp/127.0.0.1:7447"]}}), end="")
drone = "usv"
<BLANKLINE>
[zenoh]
listen = ["tcp/127.0.0.1:7447"]
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_SHORT = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def string(text: str) -> str:
    """A TOML basic string holding exactly ``text``: quote, backslash and every
    control character (U+0000-U+001F, U+007F) escaped; other text kept as is."""
    out = []
    for ch in text:
        if ch in _SHORT:
            out.append(_SHORT[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def key(name: str) -> str:
    return name if _BARE_KEY.fullmatch(name) else string(name)


def value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"TOML: not a finite number: {v!r}")
        return repr(v)
    if isinstance(v, str):
        return string(v)
    if isinstance(v, Sequence):
        return "[" + ", ".join(value(x) for x in v) + "]"
    raise TypeError(f"TOML: cannot write a value of type {type(v).__name__}")


def dumps(doc: Mapping[str, Any]) -> str:
    """``doc`` as TOML: its scalar keys first, then one ``[table]`` per mapping
    (nested mappings as ``[a.b]``)."""
    lines: list[str] = []
    _table(doc, [], lines)
    return "\n".join(lines) + "\n"


def _table(doc: Mapping[str, Any], path: list[str], lines: list[str]) -> None:
    tables = [(k, v) for k, v in doc.items() if isinstance(v, Mapping)]
    for k, v in doc.items():
        if not isinstance(v, Mapping):
            lines.append(f"{key(k)} = {value(v)}")
    for k, v in tables:
        sub = [*path, k]
        if lines:
            lines.append("")
        lines.append("[" + ".".join(key(p) for p in sub) + "]")
        _table(v, sub, lines)
