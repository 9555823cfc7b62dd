"""Reading a delivered value (``schemas/delivered_value.schema.json``) as its
contract's type, for the consumers that take its fields one by one (the
backend's 3D scene and Foxglove server, the ROS 2 and PlotJuggler bridges):
they hold a :class:`~modd_contracts.types_gen.DeliveredValue`, so mypy checks every
field name they read (``delivered.get("value")``, ``delivered["end_ns"]``).

>>> doc = load_delivered(b'{"topic": "usv.a.z", "value": 1.5}')
>>> doc is not None and doc.get("value")
1.5
>>> load_delivered(b"[1, 2]") is None, load_delivered(b"{") is None
(True, True)

The object is not validated beyond being a JSON object: a reader takes each
field defensively (a missing or mistyped field skips the value), as before.
``modd.subbroker.payload.DeliveredValue.from_json`` is the validating reader.
"""

from __future__ import annotations

import json
from typing import cast

from .types_gen import DeliveredValue


def load_delivered(raw: bytes | str) -> DeliveredValue | None:
    """``raw`` parsed as a delivered value's JSON object; None when it is not
    JSON, not UTF-8, nested past the parser's recursion, or not an object."""
    try:
        data = json.loads(raw)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None
    return as_delivered(data)


def as_delivered(data: object) -> DeliveredValue | None:
    """An already parsed JSON value as a delivered value, when it is an object."""
    return cast(DeliveredValue, data) if isinstance(data, dict) else None
