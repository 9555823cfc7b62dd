"""The delivered value: one window of one subscription, as it is put on zenoh
(``modd/<drone>/sub/<subscriber>``) and written on a TCP delivery connection
(one JSON object per line). The format is documented in docs/subbroker.md.

>>> v = DeliveredValue("sub_5", "usv.a.z", "MIN", "0.25", "METER", 1, 7, 0, 250_000_000,
...                    -0.5, None, 0)
>>> DeliveredValue.from_json(v.to_json()) == v
True

The SubBroker's hot path does not build these objects: :class:`StreamPayload`
encodes one window once for all its subscribers and gives each one the same
bytes as :meth:`DeliveredValue.to_json` (tests hold the two to each other).

>>> head = StreamPayload("usv.a.z", "MIN", "0.25", "METER", 1)
>>> tail = head.tail(7, 0, 250_000_000, -0.5, None, 0)
>>> subscriber_prefix("sub_5") + tail == v.to_json()
True
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import TYPE_CHECKING, Any, cast

from modd_contracts.types_gen import (
    DELIVERED_VALUE_REQUIRED,
    DELIVERED_VALUE_VERSION,
    DeliveredValueFields,
)
from modd_contracts.types_gen import DeliveredValue as DeliveredValueDoc

if TYPE_CHECKING:  # a type only: the subscriber client carries this module without the planner
    from modd_plan.windows import Value

#: Version of the payload (the contract's ``x-version``); a reader rejects a higher one.
PAYLOAD_VERSION = DELIVERED_VALUE_VERSION
#: Nesting a delivered value may have (an ALL window is a list: depth 2).
MAX_DEPTH = 8
#: The text and the integer fields, by the contract's types.
_TEXT = tuple(f.name for f in fields(DeliveredValueFields) if f.type == "str")
_INTS = tuple(f.name for f in fields(DeliveredValueFields) if f.type == "int")
#: The fields every payload carries, in the contract's order: the subscriber,
#: the five a stream's windows share, the six of one window, the version.
_ORDER = DELIVERED_VALUE_REQUIRED
_FIRST, _CONSTANT, _WINDOW, _VERSION = _ORDER[0], _ORDER[1:6], _ORDER[6:12], _ORDER[12:]
#: What goes before each of one window's values (the first is in the stream's
#: head), and the version that closes the payload: ``,"start_ns":`` and so on.
_KEYS = tuple(f',"{k}":' for k in _WINDOW)
_K1, _K2, _K3, _K4, _K5 = _KEYS[1:]
_END = "".join(f',"{k}":{PAYLOAD_VERSION}' for k in _VERSION) + "}"
#: The window's identity (docs/fleet.md): optional in the contract (older payloads lack
#: it), written by every SubBroker after the windows' own fields, before the version.
IDENTITY = ("drone", "epoch_ns", "window")


#: Numbers JSON cannot hold travel as these strings (docs/protocol.md, "Values JSON
#: cannot hold"): a float sum beyond the double range, ``inf − inf``.
NON_FINITE: dict[str, float] = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float as its escape string (lists element-wise).

    >>> json_safe([1.0, float("inf"), -float("inf"), float("nan"), True])
    [1.0, 'Infinity', '-Infinity', 'NaN', True]
    """
    if type(value) is float and not math.isfinite(value):
        return "NaN" if value != value else "Infinity" if value > 0 else "-Infinity"
    if isinstance(value, list):
        return [json_safe(x) for x in value]
    return value


def from_json_safe(value: Any) -> Any:
    """The inverse of :func:`json_safe`: escape strings back to floats."""
    if isinstance(value, str) and value in NON_FINITE:
        return NON_FINITE[value]
    if isinstance(value, list):
        return [from_json_safe(x) for x in value]
    return value


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_scalar(v: Any) -> bool:
    return isinstance(v, int | float | bool)


def json_depth_error(raw: bytes | str, limit: int = MAX_DEPTH) -> str | None:
    """Where ``raw`` nests deeper than ``limit`` (byte offset), or None; the
    check runs before parsing, so no input reaches the parser's recursion.

    >>> json_depth_error(b'{"a":[[[1]]]}', 3)
    'JSON nested deeper than 3 levels at byte 7'
    """
    data = raw.encode() if isinstance(raw, str) else raw
    depth, in_string, escaped = 0, False, False
    for i, c in enumerate(data):
        if in_string:
            if escaped:
                escaped = False
            elif c == 0x5C:  # backslash
                escaped = True
            elif c == 0x22:
                in_string = False
        elif c == 0x22:
            in_string = True
        elif c in (0x5B, 0x7B):
            depth += 1
            if depth > limit:
                return f"JSON nested deeper than {limit} levels at byte {i}"
        elif c in (0x5D, 0x7D):
            depth -= 1
    return None


@dataclass(frozen=True)
class DeliveredValue(DeliveredValueFields):
    """One window of a subscription: the fields are the contract's
    (``schemas/delivered_value.schema.json``, generated into
    :class:`modd_contracts.types_gen.DeliveredValueFields`), the methods read and
    write the payload.

    ``value`` is ``None`` when the window had no sample (the link's presence
    bitmap marked it absent). ``count`` is the number of samples behind the
    value when the aggregation carries it (AVERAGE, COUNT, ALL), else ``None``.
    Times are nanoseconds since the Unix epoch on the drone's clock: the
    window is ``[start_ns, end_ns)``. ``backfilled`` is true for a window
    recomputed from the drone's archive after the link missed it
    (docs/protocol.md, "Backfill"); on the wire only when true, so live
    payloads keep their bytes.
    """

    def to_dict(self) -> DeliveredValueDoc:
        out = cast(DeliveredValueDoc, asdict(self))
        out["value"] = json_safe(self.value)
        if not self.backfilled:
            del out["backfilled"]
        for name in IDENTITY:
            if out.get(name) is None:
                out.pop(name, None)  # type: ignore[misc]
        for optional in ("event_ns", "coalesced"):  # an event window's only
            if out.get(optional) is None:
                del out[optional]  # type: ignore[misc]
        out["v"] = PAYLOAD_VERSION
        return out

    def to_json(self) -> bytes:
        """Compact UTF-8 JSON (no spaces), without a trailing newline."""
        return json.dumps(self.to_dict(), separators=(",", ":"), allow_nan=False).encode()

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> DeliveredValue:
        doc = cast(DeliveredValueDoc, data)  # its fields are checked below
        version: object = doc.get("v", PAYLOAD_VERSION)
        if not isinstance(version, int) or version > PAYLOAD_VERSION:
            raise ValueError(f"unsupported delivered-value version {version!r}")
        missing = [k for k in _ORDER if k not in data and k not in _VERSION]
        if missing:
            raise ValueError(f"delivered value lacks {', '.join(missing)}")
        for name in _TEXT:
            if not isinstance(data[name], str):
                raise ValueError(f"delivered value: {name} is {data[name]!r}, not a string")
        for name in _INTS:
            if not _is_int(data[name]):
                raise ValueError(f"delivered value: {name} is {data[name]!r}, not an integer")
        value, count = from_json_safe(doc["value"]), doc["count"]
        if not (
            value is None
            or _is_scalar(value)
            or (isinstance(value, list) and all(_is_scalar(x) for x in value))
        ):
            raise ValueError(
                f"delivered value: value is {str(value)[:80]}, not a number, a "
                "boolean, a list of them or null"
            )
        if count is not None and not _is_int(count):
            raise ValueError(f"delivered value: count is {count!r}, not an integer or null")
        _check_identity(data)
        got = {f.name: data[f.name] for f in fields(cls) if f.name in data}
        out = cls(**{**got, "value": value})
        if not isinstance(out.backfilled, bool):
            raise ValueError("delivered value: backfilled must be true or false")
        if out.event_ns is not None and not (
            isinstance(out.event_ns, list) and all(_is_int(t) for t in out.event_ns)
        ):
            raise ValueError("delivered value: event_ns must be a list of integers")
        if out.coalesced is not None and not (_is_int(out.coalesced) and out.coalesced >= 0):
            raise ValueError("delivered value: coalesced must be an integer >= 0")
        return out

    @classmethod
    def from_json(cls, raw: bytes | str) -> DeliveredValue:
        """Parse one payload; ValueError (with where) for anything malformed,
        over-deep JSON included (never a RecursionError)."""
        if (deep := json_depth_error(raw)) is not None:
            raise ValueError(deep)
        data = json.loads(raw)
        if not isinstance(data, dict):
            raise ValueError("a delivered value is a JSON object")
        return cls.from_dict(data)


def _check_identity(data: Mapping[str, Any]) -> None:
    """The identity's fields, when present, are a name and two integers."""
    drone = data.get("drone")
    if drone is not None and not isinstance(drone, str):
        raise ValueError(f"delivered value: drone is {drone!r}, not a string")
    for name in IDENTITY[1:]:
        if data.get(name) is not None and not _is_int(data[name]):
            raise ValueError(f"delivered value: {name} is {data[name]!r}, not an integer")


def window_index(start_ns: int, epoch_ns: int, period_ns: int) -> int:
    """The index of the window starting at ``start_ns`` on the grid of a configuration
    whose epoch is ``epoch_ns``: windows are [epoch + k period, epoch + (k + 1) period).

    >>> window_index(1_500, 1_000, 250), window_index(1_000, 1_000, 250)
    (2, 0)
    """
    return (start_ns - epoch_ns) // period_ns


def subscriber_prefix(subscriber: str) -> bytes:
    """The start of every payload for ``subscriber``: ``{"subscriber":"NAME",``."""
    return b"{" + json.dumps(_FIRST).encode() + b":" + json.dumps(subscriber).encode() + b","


def _json_scalar(value: Value) -> str:
    """``json.dumps(value)`` with the compact separators, fast for the usual types."""
    if type(value) is float and math.isfinite(value):
        return float.__repr__(value)
    if type(value) is int:
        return int.__repr__(value)
    if value is None:
        return "null"
    return json.dumps(json_safe(value), separators=(",", ":"), allow_nan=False)


class StreamPayload:
    """The payload of one routed stream of one running config, without its
    first field: everything constant (topic, aggregation, period, unit,
    config id) is encoded once; :meth:`tail` adds one window's fields.
    ``subscriber_prefix(name) + tail`` is the subscriber's payload, byte for
    byte :meth:`DeliveredValue.to_json` (field order and separators included).
    """

    __slots__ = ("_epoch", "_head", "_id", "_period")

    def __init__(
        self,
        topic: str,
        aggregation: str,
        period_s: str,
        unit: str,
        config_id: int,
        identity: tuple[str, int, int] | None = None,
    ) -> None:
        """``identity``: (drone, epoch_ns, period_ns) of the windows, which then carry
        their identity (drone, subscriber, epoch_ns, window); None: they do not."""
        fixed = json.dumps(
            dict(zip(_CONSTANT, (topic, aggregation, period_s, unit, config_id), strict=True)),
            separators=(",", ":"),
        )
        self._head = fixed[1:-1] + _KEYS[0]
        self._id, self._epoch, self._period = "", 0, 1
        if identity is not None:
            drone, self._epoch, self._period = identity
            self._id = f',"drone":{json.dumps(drone)},"epoch_ns":{self._epoch},"window":'

    def tail(
        self,
        slot: int,
        start_ns: int,
        end_ns: int,
        value: Value,
        count: int | None,
        delivered_ns: int,
        events: str = "",
    ) -> bytes:
        """``events``: an event window's fields, :func:`event_fields`."""
        ident = f"{self._id}{(start_ns - self._epoch) // self._period}" if self._id else ""
        return (
            f"{self._head}{slot}{_K1}{start_ns}{_K2}{end_ns}{_K3}{_json_scalar(value)}"
            f"{_K4}{_json_scalar(count)}{_K5}{delivered_ns}{ident}{events}{_END}"
        ).encode()


def event_fields(event_ns: list[int], coalesced: int) -> str:
    """An event window's fields as :meth:`DeliveredValue.to_json` writes them.

    >>> event_fields([5, 7], 0)
    ',"event_ns":[5,7],"coalesced":0'
    """
    return f',"event_ns":[{",".join(map(str, event_ns))}],"coalesced":{coalesced}'
