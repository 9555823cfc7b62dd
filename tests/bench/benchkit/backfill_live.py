"""Live latency with and without a running backfill, side by side in one run (issue 15's
target "live windows keep their latency: p99 within 10 % of the run without backfill").

Scenario 1 over the udp link through the radio emulator (modd-radio) at ``rate`` B/s,
the model's ``Link.rateBps`` the same (so a backfill is paced at the spare budget: the
radio's bytes/s minus the plan's live bytes/s), the real PubBroker and SubBroker, the
publisher load at the sensors' rates. The radio goes dark once for ``outage_s`` (under
the PubBroker's 90 s keep-alive, so the running config resumes) after the config runs:
every subscriber misses those windows, the drone archives them. Then, in pairs, a phase
with no backfill and a phase with one (one subscriber's gaps filled, from the request
through the SubBroker's ``modd/<drone>/backfill`` queryable to DONE) alternate, one pair
per 0.25 s subscriber; the order swaps every pair, so drifting machine load weighs on
both. Latency of a live value: the end of its window (the slot date, on this machine's
clock) to its receipt at a zenoh subscriber of the SubBroker, as bench_latency.py
measures it; backfilled values are left out."""

from __future__ import annotations

import json
import os
import re
import statistics
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from modd.ports import free_port
from modd.subbroker.payload import DeliveredValue
from modd.zenoh_session import client_settings, open_session, wait_connected
from radio_harness import start_pubbroker_dgram, start_radio_udp, subbroker_dgram_config
from subbroker_harness import (
    Proc,
    model_copy,
    processes,
    shared_credentials,
    start_load,
    start_subbroker,
    wait_port,
)

# One pair per subscriber whose gap takes seconds to fill (sub_1 and sub_2, 2 s windows,
# take less than one at these rates).
ORDER = ["sub_3", "sub_4", "sub_5", "sub_6", "sub_7"]


DOWN = re.compile(r"drone->base passed (\d+) \((\d+) B\), dropped \d+ \(([^)]*)\)")


def radio_down(radio: Proc) -> tuple[int, int]:
    """(bytes passed, datagrams dropped for the queue) drone -> base so far, from the
    emulator's last report (every second)."""
    for line in reversed(radio.log().splitlines()):
        m = DOWN.search(line)
        if m:
            queue = re.search(r"queue (\d+)", m.group(3))
            return int(m.group(2)), int(queue.group(1)) if queue else 0
    return 0, 0


@dataclass
class Phase:
    backfill: bool
    latencies_ns: list[int] = field(default_factory=list)
    seconds: float = 0.0
    windows: int = 0  # backfilled windows delivered in the phase
    bytes: int = 0
    radio_bytes: int = 0  # drone -> base through the radio (payloads)
    queue_drops: int = 0  # datagrams the radio dropped: more offered than its rate

    def radio_bps(self) -> float:
        """Drone -> base bytes/s through the radio (its reports are 1 s apart: the span
        counted is the phase plus the 1.1 s waited for the report after it)."""
        return self.radio_bytes / (self.seconds + 1.1) if self.seconds else 0.0

    def p(self, q: float) -> float:
        xs = sorted(self.latencies_ns)
        return xs[min(len(xs) - 1, int(q * len(xs)))] / 1e6 if xs else float("nan")


class Receiver:
    """Every delivered value with its receipt time; the live ones' latencies per phase."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.phase: Phase | None = None
        self.live = 0

    def on_sample(self, sample: Any) -> None:
        now = time.time_ns()
        if "/sub/" not in str(sample.key_expr):
            return
        v = DeliveredValue.from_json(sample.payload.to_bytes())
        if v.backfilled or v.value is None:
            return
        with self.lock:
            self.live += 1
            if self.phase is not None:
                self.phase.latencies_ns.append(now - v.end_ns)


def _ask(session: Any, request: dict[str, Any]) -> dict[str, Any]:
    for reply in session.get("modd/usv/backfill", payload=json.dumps(request), timeout=10.0):
        if reply.ok is not None:
            out: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
            return out
    raise RuntimeError(f"no reply from the backfill queryable to {request}")


def _measure(
    rx: Receiver, radio: Proc, phase: Phase, session: Any | None, subscriber: str, seconds: float
) -> Phase:
    """One phase: ``seconds`` without a backfill, or ``subscriber``'s gaps filled from the
    request to DONE (cancelled after 4 x ``seconds``)."""
    t0 = time.monotonic()
    b0, q0 = radio_down(radio)
    with rx.lock:
        rx.phase = phase
    if session is None:
        time.sleep(seconds)
    else:
        job = _ask(session, {"op": "start", "subscriber": subscriber, "gaps": True})
        if job.get("status") not in ("RUNNING", "DONE"):
            raise RuntimeError(f"backfill of {subscriber} refused: {job}")
        while job["status"] == "RUNNING" and time.monotonic() - t0 < 4 * seconds:
            time.sleep(0.1)
            job = _ask(session, {"op": "progress", "id": job["id"]})
        if job["status"] == "RUNNING":
            job = _ask(session, {"op": "cancel", "id": job["id"]})
        phase.windows, phase.bytes = int(job["windows"]), int(job["bytes"])
    with rx.lock:
        rx.phase = None
    phase.seconds = time.monotonic() - t0
    time.sleep(1.1)  # the radio's next report
    b1, q1 = radio_down(radio)
    phase.radio_bytes, phase.queue_drops = b1 - b0, q1 - q0
    return phase


def run(
    tmp: Path, rate: int, outage_s: float, seconds: float, pairs: int
) -> tuple[list[tuple[Phase, Phase]], dict[str, Any]]:
    """``pairs`` (without, with) phases after one outage; and the run's facts."""
    model_path = model_copy(tmp, "scenario1.modd")
    model = json.loads(model_path.read_text())
    model["link"] = {"transport": "udp", "rateBps": rate}
    model_path.write_text(json.dumps(model))
    zport, ingress, port, relay = free_port(), free_port(), free_port("udp"), free_port("udp")
    settle = 12.0  # handshake, CONFIG, first live values before the radio goes dark
    pb = start_pubbroker_dgram(tmp, model_path, {"transport": "udp", "port": port}, ingress)
    radio = start_radio_udp(
        tmp, port, f"rate={rate},outage={settle}+{outage_s},seed=1", relay=relay
    )[0]
    sb = start_subbroker(
        tmp, subbroker_dgram_config(tmp, model_path, f"127.0.0.1:{relay}", zport, "udp")
    )
    load = start_load(tmp, model_path, ingress, settle + outage_s + pairs * 6 * seconds + 120)
    session = None
    out: list[tuple[Phase, Phase]] = []
    facts: dict[str, Any] = {"load_before": os.getloadavg()}
    try:
        wait_port(zport, 60)
        session = open_session(
            client_settings(f"tcp/127.0.0.1:{zport}", shared_credentials().cred_file("backend"))
        )
        if not wait_connected(session, 60) or not sb.wait_log("running", 60):
            raise RuntimeError(f"the SubBroker is not running: {sb.log()[-2000:]}")
        rx = Receiver()
        session.declare_subscriber("modd/usv/sub/*", rx.on_sample)
        began = time.monotonic()
        time.sleep(max(0.0, settle + outage_s + 6.0 - (time.monotonic() - began)))
        if rx.live == 0:
            raise RuntimeError("no live value reached the base station")
        for i, sub in enumerate(ORDER[:pairs]):
            quiet, busy = Phase(False), Phase(True)
            for p in (quiet, busy) if i % 2 == 0 else (busy, quiet):
                _measure(rx, radio, p, session if p.backfill else None, sub, seconds)
            out.append((quiet, busy))
        facts["load_after"] = os.getloadavg()
        facts["radio"] = [ln for ln in radio.log().splitlines() if ln.startswith("radio:")][-1:]
    finally:
        if session is not None:
            session.close()  # type: ignore[no-untyped-call]
        with processes(load, radio, pb, sb):
            pass
    return out, facts


def report(
    pairs: list[tuple[Phase, Phase]], facts: dict[str, Any]
) -> tuple[list[list[object]], float]:
    """Rows per pair and the summary; returns (rows, ratio of the medians of p99)."""
    rows: list[list[object]] = []
    for i, (quiet, busy) in enumerate(pairs):
        rows.append(
            [
                ORDER[i],
                len(quiet.latencies_ns),
                f"{quiet.p(0.5):.0f}",
                f"{quiet.p(0.99):.0f}",
                len(busy.latencies_ns),
                f"{busy.p(0.5):.0f}",
                f"{busy.p(0.99):.0f}",
                busy.windows,
                f"{busy.bytes / busy.seconds:.0f}" if busy.seconds else "—",
                f"{quiet.radio_bps():.0f} / {busy.radio_bps():.0f}",
                f"{quiet.queue_drops} / {busy.queue_drops}",
            ]
        )
    med_quiet = statistics.median(q.p(0.99) for q, _ in pairs)
    med_busy = statistics.median(b.p(0.99) for _, b in pairs)
    all_quiet = Phase(False, [x for q, _ in pairs for x in q.latencies_ns])
    all_busy = Phase(True, [x for _, b in pairs for x in b.latencies_ns])
    rows.append(["median", "", "", f"{med_quiet:.0f}", "", "", f"{med_busy:.0f}", "", "", "", ""])
    rows.append(
        [
            "pooled",
            len(all_quiet.latencies_ns),
            f"{all_quiet.p(0.5):.0f}",
            f"{all_quiet.p(0.99):.0f}",
            len(all_busy.latencies_ns),
            f"{all_busy.p(0.5):.0f}",
            f"{all_busy.p(0.99):.0f}",
            sum(b.windows for _, b in pairs),
            "",
            "",
            f"{sum(q.queue_drops for q, _ in pairs)} / {sum(b.queue_drops for _, b in pairs)}",
        ]
    )
    return rows, med_busy / med_quiet
