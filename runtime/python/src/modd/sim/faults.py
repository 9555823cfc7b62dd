"""Faults injected into the simulated sensors, for testing quality control:
a **spike** (one sample offset) and a **flat line** (a topic stuck at its
value for a while). Written, while the simulator runs, to a JSON file named
by ``modd-sim --faults FILE`` (or ``MODD_SIM_FAULTS``, which ``modd up
--simulate`` passes on); read again whenever it changes::

    {"faults": [
      {"topic": "usv.ctd.t", "kind": "spike", "at": 1790000000.0, "offset": 500},
      {"topic": "usv.ctd.t", "kind": "flat", "from": 1790000010.0, "to": 1790000030.0}
    ]}

``at``, ``from`` and ``to`` are Unix seconds on the simulator's clock: the spike
is the first sample at or after ``at``; the flat line holds the value of the
first sample at or after ``from`` until ``to``. A file that cannot be read is
said once on stderr and ignored (the sensors keep running).

>>> f = Faults.parse({"faults": [{"topic": "a", "kind": "spike", "at": 1.0, "offset": 5}]})
>>> [f.apply("a", t, 1.0) for t in (0.5, 1.0, 1.5)]
[1.0, 6.0, 1.0]
>>> g = Faults.parse({"faults": [{"topic": "a", "kind": "flat", "from": 1.0, "to": 2.0}]})
>>> [g.apply("a", t, v) for t, v in ((0.5, 0.1), (1.0, 0.2), (1.5, 0.3), (2.0, 0.4))]
[0.1, 0.2, 0.2, 0.4]
"""

from __future__ import annotations

import json
import os
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


@dataclass
class Fault:
    topic: str
    kind: str  # "spike" or "flat"
    start: float
    end: float  # a spike: unused (one sample)
    offset: float = 0.0
    done: bool = False  # a spike applied, once
    held: float | None = None  # a flat line's value


@dataclass
class Faults:
    faults: list[Fault] = field(default_factory=list)

    @staticmethod
    def parse(doc: Any) -> Faults:
        """The faults of a parsed file; ValueError naming the entry at fault."""
        items = doc.get("faults") if isinstance(doc, dict) else None
        if not isinstance(items, list):
            raise ValueError('a JSON object {"faults": [...]}')
        out = []
        for i, f in enumerate(items):
            try:
                if f["kind"] == "spike":
                    out.append(
                        Fault(str(f["topic"]), "spike", float(f["at"]), 0.0, float(f["offset"]))
                    )
                elif f["kind"] == "flat":
                    out.append(Fault(str(f["topic"]), "flat", float(f["from"]), float(f["to"])))
                else:
                    raise ValueError(f"kind {f['kind']!r}: spike or flat")
            except (KeyError, TypeError, ValueError) as exc:
                raise ValueError(f"faults[{i}]: {exc}") from None
        return Faults(out)

    def apply(self, topic: str, t: float, value: Any) -> Any:
        """The value published for ``topic`` at ``t`` (Unix seconds), faults applied."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            return value
        for f in self.faults:
            if f.topic != topic:
                continue
            if f.kind == "spike" and not f.done and t >= f.start:
                f.done = True
                value = value + f.offset
            elif f.kind == "flat" and f.start <= t < f.end:
                if f.held is None:
                    f.held = float(value)
                value = f.held
        return value


class FaultFile:
    """The faults of a file, read again when it changes (shared by the publishers' threads)."""

    def __init__(self, path: str | None) -> None:
        self.path = Path(path) if path else None
        self._lock = threading.Lock()
        self._stamp: tuple[int, int] | None = None
        self._faults = Faults()

    def apply(self, topic: str, t: float, value: Any) -> Any:
        if self.path is None:
            return value
        with self._lock:
            self._reload()
            return self._faults.apply(topic, t, value)

    def _reload(self) -> None:
        assert self.path is not None
        try:
            st = os.stat(self.path)
        except OSError:
            return  # not written yet
        stamp = (st.st_mtime_ns, st.st_size)
        if stamp == self._stamp:
            return
        self._stamp = stamp
        try:
            self._faults = Faults.parse(json.loads(self.path.read_text(encoding="utf-8")))
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            print(f"modd-sim: {self.path}: {exc}; no fault injected", file=sys.stderr)
            self._faults = Faults()
