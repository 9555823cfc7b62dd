"""The ROS 2 messages of MoDD's values and their CDR (via ``rosbags``):

- ``modd_msgs/msg/Window``: one window of a subscription (start, end, value,
  sample count, aggregation); its ``.msg`` and ``package.xml`` are generated
  for the integrator (``modd generate --target ros2``, docs/ecosystem.md);
- ``std_msgs/msg/Float64``: the plain value.

An empty window (no sample) has ``value`` NaN and ``count`` 0. An ``ALL``
window has ``value`` NaN, its samples in ``samples`` and ``count`` their
number. ``has_count`` says whether ``count`` is known: the drone does not send
it for a non-empty MIN, MAX or LAST window (``count`` 0 then means unknown).

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

TIME = MessageType(
    "builtin_interfaces/msg/Time", (Field("sec", "int32"), Field("nanosec", "uint32"))
)
FLOAT64 = MessageType("std_msgs/msg/Float64", (Field("data", "float64"),))
WINDOW = MessageType(
    "modd_msgs/msg/Window",
    (
        Field("window_start", TIME.name),
        Field("window_end", TIME.name),
        Field("value", "float64"),
        Field("count", "uint32"),
        Field("aggregation", "string"),
        Field("has_count", "bool"),
        Field("samples", "float64[]"),
    ),
)
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


def window_cdr(
    start_ns: int, end_ns: int, value: Any, count: int | None, aggregation: str
) -> bytes:
    """CDR (little endian, with its 4-byte encapsulation header)."""
    import numpy as np

    store = typestore()
    W = store.types[WINDOW.name]
    samples = [as_float(v) for v in value] if isinstance(value, list) else []
    if isinstance(count, int) and not isinstance(count, bool):
        n: int | None = count
    elif value is None or isinstance(value, list):
        n = len(samples)  # an empty window holds 0 samples, an ALL window its list
    else:
        n = None  # MIN, MAX, LAST: the drone does not say how many
    msg = W(
        window_start=_time(start_ns),
        window_end=_time(end_ns),
        value=as_float(value),
        count=n or 0,
        aggregation=aggregation,
        has_count=n is not None,
        samples=np.asarray(samples, dtype=np.float64),
    )
    return bytes(store.serialize_cdr(msg, WINDOW.name))


def float64_cdr(value: Any) -> bytes:
    store = typestore()
    F = store.types[FLOAT64.name]
    return bytes(store.serialize_cdr(F(data=as_float(value)), FLOAT64.name))
