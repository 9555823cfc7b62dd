"""One measured run of one system at one scenario's load: start it, let it settle, then
capture the link (tshark), sample the drone-side broker (/proc) and count deliveries over
the same ``seconds``; stop everything by PID."""

from __future__ import annotations

import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[3]
for _p in (REPO / "tests" / "subbroker", REPO / "tests" / "bench"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

from .capture import Capture, Wire  # noqa: E402
from .footprint import Footprint, Sampler  # noqa: E402
from .scenario import Scenario  # noqa: E402
from .systems import SYSTEMS, Delivery  # noqa: E402


@dataclass
class Run:
    kind: str  # modd | mosquitto | zenoh
    system: str
    scenario: Scenario
    seconds: float
    wire: Wire | None
    footprint: Footprint | None
    delivery: Delivery
    extra: dict[str, Any]


def measure(
    kind: str,
    sc: Scenario,
    seconds: float,
    *,
    capture: bool = True,
    footprint: bool = True,
    settle_s: float = 1.0,
) -> Run:
    """``kind``: modd | mosquitto | zenoh."""
    with tempfile.TemporaryDirectory(prefix=f"modd-bench-{kind}-") as d:
        tmp = Path(d)
        system = SYSTEMS[kind](tmp, sc, seconds)
        extra: dict[str, Any] = {}
        try:
            time.sleep(settle_s)  # steady state: handshakes, CONFIG, SUBSCRIBE not counted
            cap = Capture(tmp, system.link_port, seconds, tag=kind) if capture else None
            sampler = Sampler(system.broker_pid).start() if footprint else None
            system.tally.mark()
            if cap is not None:
                wire = cap.wait()
            else:
                wire = None
                time.sleep(seconds)
            delivery = system.tally.freeze()
            fp = sampler.stop() if sampler is not None else None
        finally:
            extra = system.stop()
    return Run(kind, system.name, sc, seconds, wire, fp, delivery, extra)
