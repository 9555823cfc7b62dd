"""The delivered value: one window of one subscription, as it is put on zenoh
(``modd/<drone>/sub/<subscriber>``) and written on a TCP delivery connection
(one JSON object per line). The format is documented in docs/subbroker.md.

>>> v = DeliveredValue("sub_5", "usv.a.z", "MIN", "0.25", "METER", 1, 7, 0, 250_000_000,
...                    -0.5, None, 0)
>>> DeliveredValue.from_json(v.to_json()) == v
True
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, fields
from typing import Any

Scalar = float | int | bool
Value = Scalar | list[Scalar] | None

#: Version of the payload; a reader rejects a higher major version.
PAYLOAD_VERSION = 1


@dataclass(frozen=True)
class DeliveredValue:
    """One window of a subscription.

    ``value`` is ``None`` when the window had no sample (the link's presence
    bitmap marked it absent). ``count`` is the number of samples behind the
    value when the aggregation carries it (AVERAGE, COUNT, ALL), else ``None``.
    Times are nanoseconds since the Unix epoch on the drone's clock: the
    window is ``[start_ns, end_ns)``.
    """

    subscriber: str
    topic: str
    aggregation: str
    period_s: str
    unit: str
    config_id: int
    slot: int
    start_ns: int
    end_ns: int
    value: Value
    count: int | None
    delivered_ns: int

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["v"] = PAYLOAD_VERSION
        return out

    def to_json(self) -> bytes:
        """Compact UTF-8 JSON (no spaces), without a trailing newline."""
        return json.dumps(self.to_dict(), separators=(",", ":")).encode()

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> DeliveredValue:
        version = data.get("v", PAYLOAD_VERSION)
        if not isinstance(version, int) or version > PAYLOAD_VERSION:
            raise ValueError(f"unsupported delivered-value version {version!r}")
        missing = [f.name for f in fields(cls) if f.name not in data]
        if missing:
            raise ValueError(f"delivered value lacks {', '.join(missing)}")
        return cls(**{f.name: data[f.name] for f in fields(cls)})

    @classmethod
    def from_json(cls, raw: bytes | str) -> DeliveredValue:
        data = json.loads(raw)
        if not isinstance(data, dict):
            raise ValueError("a delivered value is a JSON object")
        return cls.from_dict(data)


def split_window(aggregation: str, window: Any) -> tuple[Value, int | None]:
    """``(value, count)`` of a window in the form of :mod:`modd_plan.derive`.

    >>> split_window("AVERAGE", (2.5, 4)), split_window("MIN", None)
    ((2.5, 4), (None, None))
    """
    if aggregation == "AVERAGE":
        return (None, 0) if window is None else (float(window[0]), int(window[1]))
    if aggregation == "COUNT":
        count = int(window or 0)
        return count, count
    if aggregation == "ALL":
        samples = list(window or [])
        return samples, len(samples)
    return window, None
