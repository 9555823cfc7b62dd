"""SubBroker throughput: CPU per delivered value on the data path (DATA windows -> fan-out
-> payload -> zenoh put), with many subscriptions.

The SubBroker runs in this process on a real zenoh session that listens on loopback; a
separate receiver process subscribes to ``modd/<drone>/sub/**`` and counts what arrives, so
every put crosses a real zenoh link. The link itself is not used: the windows of each slot
are built from the planner's own slot table (the one the receiver of the link codec walks)
and handed to ``SubBroker.on_windows`` as the link thread would. CPU is this process's
(``time.process_time``: every thread, zenoh's included).

Two phases per run:
- *paced*: the model's own rate (slots at their dates, ``--speed`` times faster), for
  ``--seconds``: CPU % of a core and CPU per value at the rate the model asks;
- *flat out*: the next slots back to back: the most values per second one core delivers.
A value counts as received when the receiver process got it (puts dropped by zenoh's
congestion control under the flat-out burst are counted apart).

    .venv/bin/python tests/bench/bench_subbroker.py                   # 4,000 subscriptions
    .venv/bin/python tests/bench/bench_subbroker.py --profile         # + the top of cProfile
    .venv/bin/python tests/bench/bench_subbroker.py --e2e --seconds 20  # the real processes

``--e2e`` runs the same model through the real processes instead: the C++ PubBroker fed by
the publisher load, the SubBroker CLI over the MoDD link, values counted by a zenoh
subscriber in this process; the SubBroker's CPU from /proc, its status (delivered,
``behind``, ``lag_s``) from ``modd/d/status``.

Target (issue 18): <= 10 us of CPU per delivered value (>= 50,000 values/s on one core).
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import random
import subprocess
import sys
import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from modd.link.frames import Config, ConfigAck, Value
from modd.link.receiver import Window
from modd.link.schedule import SlotIterator
from modd.ports import free_port
from modd.subbroker.broker import SubBroker
from modd.subbroker.config import DeliveryOptions, SubBrokerConfig
from modd.subbroker.kept import Deployment
from modd.zenoh_session import ZenohSettings, open_session

PERIODS = ["0.25", "0.5", "1.0", "2.0"]
AGGREGATIONS = ["MIN", "MAX", "AVERAGE", "LAST", "COUNT"]

RECEIVER = """
import sys, time
from modd.zenoh_session import open_session, client_settings
s = open_session(client_settings(sys.argv[1]))
n = [0]
def on_sample(sample): n[0] += 1
sub = s.declare_subscriber(sys.argv[2], on_sample)
print("ready", flush=True)
for line in sys.stdin:
    time.sleep(0.5)   # what is on its way arrives
    print(n[0], flush=True)
"""


def model(n_topics: int, n_subs: int, seed: int = 1) -> dict[str, Any]:
    """One publisher of ``n_topics`` float32 topics at 25 Hz; ``n_subs`` subscriptions to
    random topics, periods (0.25-2 s) and aggregations: some sent, most derived."""
    rng = random.Random(seed)
    names = [f"v{j}" for j in range(n_topics)]
    topics = [f"d.s.{n}" for n in names]
    return {
        "schemaVersion": "1.0",
        "drone": {
            "name": "d",
            "sensors": [{"name": "s", "variables": [{"name": n, "unit": "METER"} for n in names]}],
        },
        "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 7171}, "logPath": "/tmp/l"},
        "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 7272}, "configPath": "/tmp/c"},
        "publishers": [{"name": "p", "periodS": "0.04", "topics": topics}],
        "subscribers": [
            {
                "name": f"sub{k}",
                "topic": rng.choice(topics),
                "periodS": rng.choice(PERIODS),
                "aggregation": rng.choice(AGGREGATIONS),
            }
            for k in range(n_subs)
        ],
    }


def slots(config: Config, epoch_ns: int, count: int, seed: int = 2) -> list[list[Window]]:
    """The windows of the first ``count`` DATA slots, with random values."""
    rng = random.Random(seed)
    periods = [s.period_us for s in config.streams]
    walk = SlotIterator(periods)
    out = []
    for _ in range(count):
        s = next(walk)
        end = epoch_ns + s.offset_us * 1000
        out.append(
            [
                Window(
                    config.config_id,
                    s.index,
                    sid,
                    end - periods[sid] * 1000,
                    end,
                    Value(True, rng.uniform(-10, 10), 0, rng.randint(1, 25), []),
                )
                for sid in s.streams
            ]
        )
    return out


@dataclass
class Phase:
    name: str
    delivered: int
    received: int
    cpu_s: float
    wall_s: float

    @property
    def us_per_value(self) -> float:
        return 1e6 * self.cpu_s / max(1, self.delivered)

    def row(self) -> str:
        return (
            f"| {self.name} | {self.delivered:,} | {self.received:,} | "
            f"{self.delivered / self.wall_s:,.0f} | {100 * self.cpu_s / self.wall_s:.0f} % | "
            f"**{self.us_per_value:.1f}** | {1e6 / self.us_per_value:,.0f} |"
        )


class Bench:
    """A SubBroker in this process, running ``m``'s plan, and the receiver process."""

    def __init__(self, m: dict[str, Any]) -> None:
        os.environ.setdefault("MODD_LINK_KEY", "bench-link-key-16b")
        port = free_port()
        self.session = open_session(ZenohSettings(mode="peer", listen=(f"tcp/127.0.0.1:{port}",)))
        self.receiver = subprocess.Popen(
            [sys.executable, "-c", RECEIVER, f"tcp/127.0.0.1:{port}", "modd/d/sub/**"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.receiver.stdout is not None and self.receiver.stdin is not None
        if self.receiver.stdout.readline().strip() != "ready":
            raise RuntimeError("the receiver process did not start")
        cfg = SubBrokerConfig(
            model=m,
            drone="d",
            link=_no_link(),
            delivery=DeliveryOptions(tcp=False, status_period_s=3600),
        )
        self.broker = SubBroker(cfg, self.session)
        self.broker.start()
        self.broker.link.stop()  # the windows come from this bench, not from a PubBroker
        config = self.broker._prepare(m, avoid=0, meta=Deployment.configured())
        self.epoch_ns = time.time_ns()
        self.broker.on_config_acked(config, ConfigAck(config.config_id, 0, self.epoch_ns))
        self.config = config

    def received(self) -> int:
        assert self.receiver.stdin is not None and self.receiver.stdout is not None
        self.receiver.stdin.write("count\n")
        self.receiver.stdin.flush()
        return int(self.receiver.stdout.readline())

    def run(
        self,
        name: str,
        batch: list[list[Window]],
        pace_s: list[float] | None,
        profile: cProfile.Profile | None = None,
    ) -> Phase:
        before, got0 = self.broker.delivered, self.received()
        cpu0, t0 = time.process_time(), time.perf_counter()
        if profile is not None:
            profile.enable()
        for i, windows in enumerate(batch):
            if pace_s is not None:
                delay = t0 + pace_s[i] - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
            self.broker.on_windows(windows)
        if profile is not None:
            profile.disable()
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - t0
        return Phase(name, self.broker.delivered - before, self.received() - got0, cpu, wall)

    def close(self) -> None:
        self.broker.stop()
        self.session.close()  # type: ignore[no-untyped-call]
        self.receiver.kill()
        self.receiver.wait(5)


def _no_link() -> Any:
    from modd.subbroker.config import LinkOptions

    return LinkOptions(endpoint=("127.0.0.1", free_port()), backoff_initial_s=60.0)


def end_to_end(m: dict[str, Any], seconds: float, gate: bool = True) -> None:
    import json
    import tempfile
    import threading
    from pathlib import Path

    here = Path(__file__).resolve().parent
    for path in (here, here.parent / "subbroker"):
        if str(path) not in sys.path:
            sys.path.insert(0, str(path))
    from benchkit.footprint import Sampler
    from modd.zenoh_session import client_settings
    from subbroker_harness import (
        shared_credentials,
        start_load,
        start_pubbroker,
        start_subbroker,
        subbroker_config,
        wait_port,
    )

    asked = float(sum(1 / Fraction(s["periodS"]) for s in m["subscribers"]))
    with tempfile.TemporaryDirectory(prefix="modd-sbbench-") as tmp_name:
        tmp = Path(tmp_name)
        model_path = tmp / "model.json"
        model_path.write_text(json.dumps(m))
        link, ingress, zport = free_port(), free_port(), free_port()
        pb = start_pubbroker(tmp, model_path, link, ingress)
        config = subbroker_config(tmp, model_path, link, zport)
        if not gate:  # zenoh on the endpoint itself (docs/security.md, "Connections per source")
            config.write_text(config.read_text() + "[zenoh.gate]\nenabled = false\n")
        sb = start_subbroker(tmp, config)
        procs = [pb, sb]
        try:
            wait_port(zport, 120)
            viewer = shared_credentials().cred_file("viewer")
            session = open_session(client_settings(f"tcp/127.0.0.1:{zport}", viewer))
            received = [0]
            status: list[dict[str, Any]] = []
            lock = threading.Lock()

            def on_value(sample: Any) -> None:
                received[0] += 1

            def on_status(sample: Any) -> None:
                with lock:
                    status.append(json.loads(sample.payload.to_bytes()))

            subs = [
                session.declare_subscriber("modd/d/sub/**", on_value),
                session.declare_subscriber("modd/d/status", on_status),
            ]
            procs.append(start_load(tmp, model_path, ingress, seconds + 120))
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline and not (status and status[-1]["delivered"]):
                time.sleep(0.2)
            # Steady state: the first slots declare one zenoh publisher per subscriber
            # (~0.6 ms each), so the SubBroker starts a few seconds behind and catches up.
            while time.monotonic() < deadline:
                time.sleep(2)
                with lock:
                    a, b = status[-5], status[-1]
                rate = (b["delivered"] - a["delivered"]) / ((b["time_ns"] - a["time_ns"]) / 1e9)
                if abs(rate - asked) < 0.1 * asked and not b.get("recv_backlog_bytes"):
                    break
            with lock:
                first = status[-1]
            got0, sampler = received[0], Sampler(sb.pid).start()
            time.sleep(seconds)
            fp = sampler.stop()
            with lock:
                last = status[-1]
            got = received[0] - got0
            delivered = last["delivered"] - first["delivered"]
            dt = (last["time_ns"] - first["time_ns"]) / 1e9
            print(
                f"End to end: PubBroker -> MoDD link -> SubBroker process -> zenoh, "
                f"{len(m['subscribers']):,} subscriptions, {asked:,.0f} values/s asked, "
                f"{fp.seconds:.0f} s\n"
            )
            frames = (last["data_frames"] - first["data_frames"]) / dt
            print(
                "| DATA frames /s | delivered /s (status) | received /s | SubBroker CPU "
                "| CPU us per value | RSS MB | behind | lag_s (last, max) | receive backlog |"
            )
            print("| ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: |")
            per_value = 1e6 * fp.cpu_seconds / max(1.0, delivered / dt * fp.seconds)
            print(
                f"| {frames:.1f} | {delivered / dt:,.0f} | {got / fp.seconds:,.0f} | "
                f"{fp.cpu_percent:.0f} % | "
                f"**{per_value:.1f}** | {fp.rss_median_kb / 1024:.0f} "
                f"| {last.get('behind')} | {last.get('lag_s')}, {last.get('max_lag_s')} | "
                f"{last.get('recv_backlog_bytes')} B |"
            )
            for sub in subs:
                sub.undeclare()  # type: ignore[no-untyped-call]
            session.close()  # type: ignore[no-untyped-call]
        finally:
            for proc in reversed(procs):
                proc.stop()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--subs", type=int, default=4000)
    ap.add_argument("--topics", type=int, default=20)
    ap.add_argument("--seconds", type=float, default=10.0, help="paced phase, model time")
    ap.add_argument("--speed", type=float, default=1.0, help="paced phase: x real time")
    ap.add_argument("--flat-slots", type=int, default=64, help="flat-out phase: slots")
    ap.add_argument("--profile", action="store_true", help="print the top of cProfile")
    ap.add_argument("--e2e", action="store_true", help="through the real processes")
    ap.add_argument("--no-gate", action="store_true", help="--e2e without the zenoh accept gate")
    args = ap.parse_args(argv)
    m = model(args.topics, args.subs)
    if args.e2e:
        end_to_end(m, args.seconds, gate=not args.no_gate)
        return 0
    bench = Bench(m)
    try:
        config = bench.config
        per_s = sum(1 / Fraction(s["periodS"]) for s in m["subscribers"])
        hyper = 2.0  # the periods' least common multiple
        n_paced = int(args.seconds * 4)  # 0.25 s slots
        n_flat = args.flat_slots
        batch = slots(config, bench.epoch_ns, 16 + n_paced + 2 * n_flat)
        warmup, paced = batch[:16], batch[16 : 16 + n_paced]
        flat, profiled = batch[16 + n_paced : 16 + n_paced + n_flat], batch[16 + n_paced + n_flat :]
        bench.run("warm-up", warmup, None)  # publishers declared, caches filled
        dates = [(w[0].end_ns - paced[0][0].end_ns) / 1e9 / args.speed for w in paced]
        profile = cProfile.Profile() if args.profile else None
        results = [
            bench.run(
                f"paced, model rate x{args.speed:g} ({float(per_s) * args.speed:,.0f} "
                "values/s asked)",
                paced,
                dates,
            ),
            bench.run("flat out (slots back to back)", flat, None),
        ]
        if profile is not None:
            results.append(bench.run("flat out, under cProfile", profiled, None, profile))
        running = bench.broker._running
        assert running is not None
        print(
            f"SubBroker data path: {args.subs:,} subscriptions on {args.topics} topics, "
            f"{len(config.streams)} streams sent, {len(running.fanout.routes())}"
            f" routed (hyperperiod {hyper:g} s), {float(per_s):,.0f} values/s asked\n"
        )
        print(
            "| phase | values delivered | received | values/s | CPU (of a core) "
            "| CPU us per value | values/s per core |"
        )
        print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
        for r in results:
            print(r.row())
        if profile is not None:
            text = io.StringIO()
            pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(12)
            print("\ncProfile of the flat-out phase (tottime):\n")
            print(text.getvalue())
    finally:
        bench.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
