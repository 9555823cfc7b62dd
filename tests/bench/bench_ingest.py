"""Ingest side by side in one run: the PubBroker (archive on) against Mosquitto's publish
ingest, each broker pinned to one core (all its threads), the load on the other core from
two blaster processes (one TCP connection each, disjoint topics) that write pre-encoded
batches as fast as the broker reads them.

- PubBroker: SAMPLES frames of float32 records (13 B: id, timestamp, value), archive on
  (MCAP, zstd chunks, fsync each flush tick); the rate is samples / time from the first
  byte until the broker, asked to stop once the load is sent, has archived everything and
  exited (its final counters are checked: every sample archived, none rejected).
- Mosquitto: QoS 0 PUBLISH packets with a 16-byte payload and no subscriber (the broker
  reads, parses and routes each one); the rate is messages / time until each connection's
  final QoS 1 PUBLISH is acknowledged (the broker has read everything before it), checked
  against $SYS/broker/publish/messages/received.

    .venv/bin/python tests/bench/bench_ingest.py [--samples 20000000] [--messages 2000000]

Goal (issue 10): PubBroker ingest >= 10x Mosquitto's. Asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parents[0] / "runtime"), str(HERE.parents[0] / "subbroker")]

from benchkit.footprint import cpu_seconds, rss_kb  # noqa: E402
from benchkit.mqtt import Mosquitto  # noqa: E402
from benchkit.report import ratio, table  # noqa: E402
from pubbroker_harness import PubBroker  # noqa: E402

BROKER_CPU, LOAD_CPU = 0, 1
CONNECTIONS = 2
TOPICS = [f"usv.ins.t{i}" for i in range(20)]


@dataclass
class Ingest:
    system: str
    unit: str
    count: int
    seconds: float
    cpu_s: float
    peak_rss_kb: int
    confirmed: int  # counted by the broker itself: archived, or $SYS publishes received
    rejected: int = 0
    main_thread_cpu_s: float | None = None  # PubBroker: the ingest thread alone

    @property
    def check(self) -> str:
        what = "archived" if self.unit == "samples" else "received ($SYS, end markers out)"
        return f"{self.confirmed:,} {what}" + (
            f", {self.rejected:,} rejected" if self.rejected else ""
        )

    @property
    def rate(self) -> float:
        return self.count / self.seconds


def pin(pid: int, cpu: int) -> None:
    """Every thread of the process onto one core."""
    for tid in os.listdir(f"/proc/{pid}/task"):
        os.sched_setaffinity(int(tid), {cpu})


def start_blasters(
    protocol: str, port: int, topics: list[list[str]], count_each: int
) -> tuple[list[subprocess.Popen[str]], float]:
    """Blasters connected and waiting; returns them and the time they were told to go."""
    procs = [
        subprocess.Popen(
            [
                "taskset",
                "-c",
                str(LOAD_CPU),
                sys.executable,
                str(HERE / "benchkit" / "blaster.py"),
                protocol,
                "--port",
                str(port),
                "--topics",
                ",".join(ts),
                "--count",
                str(count_each),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        for ts in topics
    ]
    for p in procs:
        assert p.stdout is not None
        if p.stdout.readline().strip() != "ready":
            for q in procs:
                q.kill()
                q.communicate()
            raise RuntimeError(f"{protocol} blaster did not connect")
    t0 = time.monotonic()
    for p in procs:
        assert p.stdin is not None
        p.stdin.write("go\n")
        p.stdin.flush()
    return procs, t0


def wait_blasters(procs: list[subprocess.Popen[str]]) -> None:
    for p in procs:
        p.communicate(timeout=600)  # also closes the pipes
        if p.returncode != 0:
            raise RuntimeError(f"blaster exited with {p.returncode}")


def split(names: list[str]) -> list[list[str]]:
    return [names[i::CONNECTIONS] for i in range(CONNECTIONS)]


class PeakRss:
    def __init__(self, pid: int) -> None:
        self.pid, self.peak, self.cpu, self.main_cpu = pid, 0, 0.0, 0.0
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()

    def _run(self) -> None:
        while not self._stop.wait(0.01):
            try:
                self.peak = max(self.peak, rss_kb(self.pid))
                self.cpu = cpu_seconds(self.pid)  # the last read before the process exits
                self.main_cpu = cpu_seconds(self.pid, self.pid)
            except (OSError, RuntimeError, ValueError):
                return

    def stop(self) -> None:
        self._stop.set()
        self._t.join()


def pubbroker(tmp: Path, total: int) -> Ingest:
    b = PubBroker(
        tmp,
        [(t, "float32") for t in TOPICS],
        archive={"queue_limit_samples": 50_000_000, "fsync": "chunk", "flush_interval_ms": 1000},
        default_buffer_size=1000,
        log_period_s=1,
    ).start()
    assert b.proc is not None
    pid = b.proc.pid
    pin(pid, BROKER_CPU)
    cpu0, main0 = cpu_seconds(pid), cpu_seconds(pid, pid)
    watch = PeakRss(pid)
    procs, t0 = start_blasters("modd", b.tcp_port, split(TOPICS), total // CONNECTIONS)
    wait_blasters(procs)
    os.kill(pid, signal.SIGTERM)  # drains: every accepted sample is archived before exit
    b.proc.wait(300)
    seconds = time.monotonic() - t0
    watch.stop()
    b.stop()
    sent = CONNECTIONS * -(-(total // CONNECTIONS) // 4096) * 4096
    last = [ln for ln in b.log().splitlines() if "samples_archived=" in ln][-1:]
    if not last:
        raise RuntimeError(f"no counters line in the PubBroker's log:\n{b.log()[-2000:]}")
    archived = int(re.findall(r"samples_archived=(\d+)", last[0])[0])
    rejected = sum(int(n) for n in re.findall(r"rejected_\w+=(\d+)", last[0]))
    return Ingest(
        "PubBroker (archive on)",
        "samples",
        sent,
        seconds,
        watch.cpu - cpu0,
        watch.peak,
        archived,
        rejected,
        watch.main_cpu - main0,
    )


def sys_counter(port: int, topic: str, at_least: int, timeout_s: float = 5.0) -> int:
    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion

    got: list[int] = []
    c = mqtt.Client(CallbackAPIVersion.VERSION2, client_id="bench-sys")
    c.on_message = lambda cl, ud, msg: got.append(int(msg.payload))
    c.connect("127.0.0.1", port)
    c.loop_start()
    c.subscribe(topic)
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not (got and got[-1] >= at_least):
        time.sleep(0.05)
    c.disconnect()
    c.loop_stop()
    return got[-1] if got else -1


def mosquitto(tmp: Path, total: int) -> Ingest:
    m = Mosquitto(tmp, sys_interval_s=1)
    pin(m.pid, BROKER_CPU)
    cpu0 = cpu_seconds(m.pid)
    watch = PeakRss(m.pid)
    topics = [t.replace(".", "/") for t in TOPICS]
    try:
        procs, t0 = start_blasters("mqtt", m.drone_port, split(topics), total // CONNECTIONS)
        wait_blasters(procs)
        seconds = time.monotonic() - t0
        cpu = cpu_seconds(m.pid) - cpu0
        watch.stop()
        sent = CONNECTIONS * -(-(total // CONNECTIONS) // 4096) * 4096
        received = sys_counter(m.link_port, "$SYS/broker/publish/messages/received", sent)
    finally:
        m.stop()
    return Ingest(
        "Mosquitto (QoS 0, no subscriber)",
        "messages",
        sent,
        seconds,
        cpu,
        watch.peak,
        received - CONNECTIONS,
    )


def run(samples: int, messages: int) -> tuple[Ingest, Ingest]:
    with tempfile.TemporaryDirectory(prefix="modd-bench-ingest-") as d:
        tmp = Path(d)
        (tmp / "pb").mkdir()
        (tmp / "mq").mkdir()
        return pubbroker(tmp / "pb", samples), mosquitto(tmp / "mq", messages)


def render(pb: Ingest, mq: Ingest) -> str:
    rows: list[list[object]] = [
        [
            r.system,
            f"{r.count:,} {r.unit}",
            r.seconds,
            r.rate,
            r.cpu_s,
            r.count / r.cpu_s if r.cpu_s else float("nan"),
            r.peak_rss_kb / 1024,
            r.check,
        ]
        for r in (pb, mq)
    ]
    if pb.main_thread_cpu_s:
        rows.append(
            [
                "PubBroker ingest thread alone (no archive work)",
                "",
                "",
                "",
                pb.main_thread_cpu_s,
                pb.count / pb.main_thread_cpu_s,
                "",
                "",
            ]
        )
    rows.append(
        [
            "ratio PubBroker / Mosquitto",
            "",
            "",
            ratio(pb.rate, mq.rate),
            "",
            ratio(pb.count / pb.cpu_s, mq.count / mq.cpu_s) if pb.cpu_s and mq.cpu_s else "—",
            "",
            "goal ≥ 10×",
        ]
    )
    return (
        f"Ingest on one core (broker pinned to cpu {BROKER_CPU}, load on cpu {LOAD_CPU}, "
        f"{CONNECTIONS} loopback TCP connections)\n\n"
        + table(
            [
                "broker",
                "sent",
                "wall s",
                "per s",
                "broker CPU-s",
                "per CPU-s",
                "peak RSS MB",
                "check",
            ],
            rows,
        )
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=20_000_000)
    ap.add_argument("--messages", type=int, default=2_000_000)
    args = ap.parse_args(argv)
    print(render(*run(args.samples, args.messages)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
