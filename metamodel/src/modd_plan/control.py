"""The link's own control traffic, drone to base: what goes on the air beside
the DATA of the plan's streams (docs/planning.md, "Control traffic").

* **STATUS** every ``status_period_s`` (the SubBroker asks for it in CONFIG,
  :data:`DEFAULT_STATUS_PERIOD_S` unless configured): over udp/serial one
  CONTROL datagram of its own (type, counter varint, the STATUS frame, tag),
  over tcp a frame in a DATA segment, counted here as a segment of its own.
  Its frame: the :class:`StatusField` counters as varints, then each
  instrument's health (``modd-sensors``' instruments, the model's sensors
  with a ``kind``). The **estimate** sizes each counter at its value after
  :data:`HORIZON_S` of the plan (ingest, DATA frames, link bytes) or, planned
  for a run of ``horizon_s``, is that run's STATUS frames, each counter at its
  value when its frame is sent, each size at its share of the frames;
  the **bound** is the link's *STATUS room* (``max_datagram - 14`` over
  udp/serial, 1,400 B over tcp: the PubBroker never sends a larger one).
* **PONG** for the SubBroker's keepalive PING every :data:`KEEPALIVE_S`
  (payload :data:`KEEPALIVE_PAYLOAD`), in a CONTROL datagram.

Left out (not per hour): the handshake and CONFIG_ACK (once per session or
CONFIG); NACK answers and backfill (losses, operator requests); a STATUS for
an instrument changing state (at most one more per ``min(period, 10 s)``:
docs/protocol.md, "The change budget"). The bound holds while the
instruments' states hold.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from modd_contracts.link_wire_gen import (
    CONTROL_TAG_BYTES,
    DEFAULT_STATUS_PERIOD_S,
    StatusField,
)

#: the SubBroker's keepalive: a PING every 30 s when nothing else went out
KEEPALIVE_S = 30
#: its payload (``b"alive"``, modd/subbroker/dgsession.py); a PONG echoes it
KEEPALIVE_PAYLOAD = 5
#: the counters' values are estimated after this much of a run
HORIZON_S = 3600
#: CONTROL datagram around one frame: type, counter (varint, about 2 B after
#: 128 datagrams, at most 5: the STATUS room is ``max_datagram`` minus the
#: largest), tag
CONTROL_HEADER_ABOUT = 1 + 2 + CONTROL_TAG_BYTES
CONTROL_HEADER_MAX = 1 + 5 + CONTROL_TAG_BYTES
#: health fields per instrument as ``modd-sensors`` sends them, with their
#: estimated widths: state, lines_ok, lines_bad, reconnects, last_value_ms
#: (Unix ms: 6 B), values, missing, refused, timeouts, exceptions, silences,
#: ignored, no_fix
HEALTH_FIELD_BYTES = (1, 3, 1, 1, 6, 3, 1, 1, 1, 1, 1, 1, 1)
#: a disk of some GB free, an archive of some kB/s (estimates)
DISK_FREE_MB, ARCHIVE_RATE_BPS = 100_000, 10_000


def varint_bytes(value: int) -> int:
    """Bytes of ``value`` as a LEB128 varint.

    >>> varint_bytes(127), varint_bytes(128), varint_bytes(3600)
    (1, 2, 2)
    """
    n = 1
    while value >= 0x80:
        value >>= 7
        n += 1
    return n


@dataclass(frozen=True)
class ControlInputs:
    """What sizes the control traffic: the STATUS period (0: none), the
    instruments whose health STATUS carries, the samples published per second."""

    status_period_s: int = DEFAULT_STATUS_PERIOD_S
    instruments: tuple[str, ...] = ()
    samples_per_s: float = 0.0
    horizon_s: int | None = None

    @staticmethod
    def of(
        model: Mapping[str, Any], status_period_s: int | None = None, horizon_s: int | None = None
    ) -> ControlInputs:
        """From a validated model (``status_period_s`` None: the default;
        ``horizon_s`` None: the frame after :data:`HORIZON_S`)."""
        sensors = model.get("drone", {}).get("sensors", [])
        rate = 0.0
        for pub in model.get("publishers", []):
            period = float(pub.get("periodS", 0) or 0)
            if period > 0:
                rate += len(pub.get("topics", [])) / period
        return ControlInputs(
            DEFAULT_STATUS_PERIOD_S if status_period_s is None else status_period_s,
            tuple(s["name"] for s in sensors if s.get("kind")),
            rate,
            None if horizon_s is None else max(1, horizon_s),
        )


@dataclass(frozen=True)
class ControlTraffic:
    """Control frames per hour, drone to base, as (frame bytes, frames per
    hour, each in its own packet): the estimate and the bound. The link
    budget adds each transport's datagram header and framing (wire bytes)."""

    status_period_s: int
    about: tuple[tuple[int, float], ...]
    at_most: tuple[tuple[int, float], ...]


def status_frame_about(
    inputs: ControlInputs,
    frames_per_s: float,
    bytes_per_s: float,
    datagrams_per_s: float,
    at_s: float = HORIZON_S,
) -> int:
    """The estimated STATUS frame (length, type, counters, health) sent ``at_s``
    into a run at the given rates."""
    h = at_s
    n = len(inputs.instruments)
    value = {
        StatusField.UPTIME_S: h,
        StatusField.SAMPLES_IN: inputs.samples_per_s * h,
        StatusField.SAMPLES_ARCHIVED: inputs.samples_per_s * h,
        StatusField.FRAMES_SENT: frames_per_s * h,
        StatusField.LINK_BYTES_SENT: bytes_per_s * h,
        StatusField.DISK_FREE_MB: DISK_FREE_MB,
        StatusField.ARCHIVE_RATE_BPS: ARCHIVE_RATE_BPS,
        StatusField.SAMPLES_PENDING: inputs.samples_per_s,
        StatusField.LINK_DATAGRAMS_SENT: datagrams_per_s * h,
        StatusField.PUBLISHERS_CONNECTED: 1 + int(n > 0),
        StatusField.INSTRUMENTS: n,
        StatusField.INSTRUMENTS_OPEN: n,
    }
    body = varint_bytes(len(StatusField))
    body += sum(varint_bytes(int(value.get(f, 0))) for f in StatusField)
    if n:
        entry = varint_bytes(len(HEALTH_FIELD_BYTES)) + sum(HEALTH_FIELD_BYTES)
        body += varint_bytes(n) + sum(
            varint_bytes(len(s)) + len(s) + entry for s in inputs.instruments
        )
    return varint_bytes(body + 1) + 1 + body


def status_frames_about(
    inputs: ControlInputs, frames_per_s: float, bytes_per_s: float, datagrams_per_s: float
) -> tuple[tuple[int, float], ...]:
    """The STATUS frames of a run of ``inputs.horizon_s`` (one every period, the
    first one period in), as (frame bytes, frames per hour): each size at its
    share of the frames (counters grow: a short run's frames are smaller);
    without a horizon, the frame after :data:`HORIZON_S`."""
    period = inputs.status_period_s
    if inputs.horizon_s is None:
        frame = status_frame_about(inputs, frames_per_s, bytes_per_s, datagrams_per_s)
        return ((frame, 3600 / period),)
    count = max(1, int(inputs.horizon_s // period))
    sizes: dict[int, int] = {}
    for k in range(1, count + 1):
        size = status_frame_about(inputs, frames_per_s, bytes_per_s, datagrams_per_s, k * period)
        sizes[size] = sizes.get(size, 0) + 1
    return tuple((size, 3600 / period * c / count) for size, c in sorted(sizes.items()))


def control_traffic(
    inputs: ControlInputs,
    room: int,
    frames_per_s: float,
    bytes_per_s: float,
    datagrams_per_s: float,
) -> ControlTraffic:
    """STATUS and PONG frames per hour; ``room``: the link's STATUS room
    (the largest STATUS frame the PubBroker sends, the bound's)."""
    pong = 2 + KEEPALIVE_PAYLOAD
    pongs = 3600 / KEEPALIVE_S
    about: list[tuple[int, float]] = [(pong, pongs)]
    at_most: list[tuple[int, float]] = [(pong, pongs)]
    period = inputs.status_period_s
    if period > 0:
        frames = status_frames_about(inputs, frames_per_s, bytes_per_s, datagrams_per_s)
        about += [(min(frame, room), n) for frame, n in frames]
        at_most.append((max(room, frames[-1][0]), 3600 / period))
    return ControlTraffic(period, tuple(about), tuple(at_most))
