"""The bridge's counters and its one-line status report.

Example::

    counters.mapped += 1
    log(status_line(counters, heartbeat_age=0.4, lost=False, system=1))
    # status: mapped 120 (samples 720), unknown 0, bad 0, ignored 35, heartbeat 0.4 s ago
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class Counters:
    mapped: int = 0  # messages from the autopilot whose fields became samples
    samples: int = 0  # samples handed to the publishers
    unknown: int = 0  # well-formed frames of a message id the dialect does not know
    bad: int = 0  # bad CRC, bad length, junk between frames, truncated frames
    ignored: int = 0  # decoded messages the model does not use, or from other systems
    unconvertible: int = 0  # field values that do not fit their topic's type
    dropped: int = 0  # samples a publisher refused (queue full)
    limited: int = 0  # messages beyond twice the rate asked (guard.RateBound)
    last_bad: str = ""  # the reason of the last bad frame


def status_line(c: Counters, heartbeat_age: float | None, lost: bool, system: int | None) -> str:
    if heartbeat_age is None:
        beat = "no HEARTBEAT yet"
    else:
        beat = f"autopilot {system} heartbeat {heartbeat_age:.1f} s ago" + (" LOST" if lost else "")
    extra = ""
    if c.unconvertible:
        extra += f", unconvertible {c.unconvertible}"
    if c.dropped:
        extra += f", dropped {c.dropped}"
    if c.limited:
        extra += f", rate-limited {c.limited}"
    last = f" (last: {c.last_bad})" if c.bad and c.last_bad else ""
    return (
        f"status: mapped {c.mapped} (samples {c.samples}), unknown {c.unknown}, "
        f"bad {c.bad}{last}, ignored {c.ignored}{extra}, {beat}"
    )
