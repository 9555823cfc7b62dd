"""Per-sensor health: what the operator needs to tell a working instrument
from a silent, unplugged or noisy one (counters, last value time, connection).

Example::

    h = Health()
    h.lines_ok += 1
    h.as_dict(now_ns)["lastValueAgeS"]
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from modd.link.frames import HEALTH_FIELDS, SensorHealth


@dataclass
class Health:
    connected: bool = False
    lines_ok: int = 0  # sentences, lines or Modbus replies that passed every check
    lines_bad: int = 0  # refused: checksum, form, CRC, truncated, garbage
    values: int = 0  # samples handed to the publishers
    missing: int = 0  # mapped fields with no value in a good line (empty, no fix, no date yet)
    refused: int = 0  # samples a publisher refused (type, range, queue full)
    reconnects: int = 0  # the device was reopened after a loss
    timeouts: int = 0  # Modbus requests with no complete reply in time
    exceptions: int = 0  # Modbus exception replies
    silences: int = 0  # times the instrument fell silent (no value for 3 periods, >= 2 s)
    ignored: int = 0  # good lines mapping nothing: other sentences, vendors', no condition met
    no_fix: int = 0  # of missing: fields of sentences that say no fix (validity.py)
    silent: bool = False
    last_value_ns: int = 0  # receive time of the last value (0: none yet)
    last_bad: str = ""  # why the last bad line was refused
    last_missing: str = ""  # why the last missing value had none
    clock_offset_ms: int | None = None  # clock = instrument: last stamp minus its receive time
    busy: str = ""  # another process holds the device ("held by pid N (name)"); not on the wire

    def no_value(self, n: int, why: str, no_fix: bool = False) -> None:
        """``n`` mapped fields gave no value, for this reason."""
        self.missing += n
        self.no_fix += n if no_fix else 0
        self.last_missing = why[:120]

    def bad(self, why: str) -> None:
        self.lines_bad += 1
        self.last_bad = why[:120]

    @property
    def state(self) -> int:
        """0 closed, 1 open, 2 silent (HEALTH_STATES): a lost device is closed, however long
        it has been silent."""
        return 0 if not self.connected else 2 if self.silent else 1

    def report(self, name: str) -> SensorHealth:
        """The sensor as the ingress's HEALTH and the link's STATUS carry it."""
        known = {**asdict(self), "state": self.state, "last_value_ms": self.last_value_ns // 10**6}
        return SensorHealth(name, tuple(int(known[f]) for f in HEALTH_FIELDS))

    def as_dict(self, now_ns: int) -> dict[str, object]:
        """The status document's per-sensor entry (camelCase, as the status is)."""
        d = asdict(self)
        out = {
            "".join(w if i == 0 else w.title() for i, w in enumerate(k.split("_"))): v
            for k, v in d.items()
        }
        out["lastValueAgeS"] = (
            round((now_ns - self.last_value_ns) / 1e9, 3) if self.last_value_ns else None
        )
        return out


def status_line(name: str, h: Health, now_ns: int) -> str:
    age = f"{(now_ns - h.last_value_ns) / 1e9:.1f} s ago" if h.last_value_ns else "none yet"
    state = (
        f"busy ({h.busy})"
        if h.busy
        else "silent"
        if h.silent
        else "open"
        if h.connected
        else "closed"
    )
    last = f" (last bad: {h.last_bad})" if h.lines_bad else ""
    last += f" (last missing: {h.last_missing})" if h.missing else ""
    extra = "".join(
        f", {k} {v}"
        for k, v in (
            ("missing", h.missing),
            ("no fix", h.no_fix),
            ("ignored", h.ignored),
            ("refused", h.refused),
            ("timeouts", h.timeouts),
            ("exceptions", h.exceptions),
        )
        if v
    )
    return (
        f"{name}: {state}, ok {h.lines_ok}, bad {h.lines_bad}{last}, values {h.values}"
        f"{extra}, reconnects {h.reconnects}, last value {age}"
    )
