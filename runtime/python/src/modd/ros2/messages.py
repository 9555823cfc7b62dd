"""The ROS 2 messages of MoDD's values and their CDR (via ``rosbags``):

- ``modd_msgs/msg/Window``: one window of a subscription (start, end, value,
  sample count, aggregation); its ``.msg`` and ``package.xml`` are generated
  for the integrator (``modd generate --target ros2``, docs/ecosystem.md);
- ``std_msgs/msg/Float64``: the plain value.

An empty window (no sample) has ``value`` NaN and ``count`` 0. An ``ALL``
window (a list of samples) has ``value`` NaN and ``count`` the list's length:
the samples themselves stay on MoDD's own keys.

>>> cdr = window_cdr(start_ns=1_500_000_000, end_ns=2_000_000_000, value=2.5, count=3,
...                  aggregation="AVERAGE")
>>> cdr[:4].hex()
'00010000'
"""

from __future__ import annotations

import math
from typing import Any

from modd_contracts.ros2 import window_msg

from .typehash import Field, MessageType, type_hash

TIME = MessageType("builtin_interfaces/msg/Time", (Field("sec", "int32"),
                                                   Field("nanosec", "uint32")))
FLOAT64 = MessageType("std_msgs/msg/Float64", (Field("data", "float64"),))
WINDOW = MessageType("modd_msgs/msg/Window", (
    Field("window_start", TIME.name),
    Field("window_end", TIME.name),
    Field("value", "float64"),
    Field("count", "uint32"),
    Field("aggregation", "string"),
))
#: The .msg text of modd_msgs/msg/Window (one source, in the contracts).
WINDOW_MSG = window_msg()

FLOAT64_HASH = type_hash(FLOAT64)
WINDOW_HASH = type_hash(WINDOW, [TIME])

_store: Any = None


def typestore() -> Any:
    """rosbags' Jazzy type store with modd_msgs/msg/Window registered."""
    global _store
    if _store is None:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        store = get_typestore(Stores.ROS2_JAZZY)
        store.register(get_types_from_msg(WINDOW_MSG, WINDOW.name))
        _store = store
    return _store


def _time(ns: int) -> Any:
    T = typestore().types[TIME.name]
    return T(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def as_float(value: Any) -> float:
    """The float a value publishes as: NaN for none, a list or a non-number."""
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float):
        return float(value)
    return math.nan


def window_cdr(start_ns: int, end_ns: int, value: Any, count: int | None,
               aggregation: str) -> bytes:
    """CDR (little endian, with its 4-byte encapsulation header)."""
    store = typestore()
    W = store.types[WINDOW.name]
    n = count if isinstance(count, int) else (len(value) if isinstance(value, list) else 0)
    msg = W(window_start=_time(start_ns), window_end=_time(end_ns), value=as_float(value),
            count=n, aggregation=aggregation)
    return bytes(store.serialize_cdr(msg, WINDOW.name))


def float64_cdr(value: Any) -> bytes:
    store = typestore()
    F = store.types[FLOAT64.name]
    return bytes(store.serialize_cdr(F(data=as_float(value)), FLOAT64.name))
