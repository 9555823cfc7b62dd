"""The three systems compared, each run on loopback at a scenario's load with the same
shape: start (drone side, then base-side subscribers), wait for steady state (every
subscriber has had a value), ``mark()`` to count from now, ``stop()``.

- ``ModdLink``: this project: the C++ PubBroker (archive on) fed by the publisher load at
  the sensors' rates, the SubBroker over the MoDD TCP link, and one ``modd.subscribe`` per
  subscriber on the SubBroker's zenoh. Configs generated from the scenario.
- ``MosquittoLink``: Mosquitto on the drone; the drone publisher sends every sample as a
  QoS 0 PUBLISH (16-byte payload); one MQTT connection (paho) per subscriber from the base.
- ``ZenohLink``: a zenoh router on the drone with egress downsampling per subscriber key at
  the subscription's rate (drops samples, no aggregation); one base-side session.

The link is the drone-side server port in every case (``link_port``); the drone-side
broker's pid is ``broker_pid``.
"""

from __future__ import annotations

import json
import statistics
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from subbroker_harness import (
    Proc,
    free_port,
    model_copy,
    shared_credentials,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from .mqtt import PAYLOAD, Mosquitto, mqtt_topic
from .scenario import Scenario

HERE = Path(__file__).resolve().parent
PYTHON = sys.executable


class Tally:
    """Values per subscriber, and latencies (ns) since mark(); thread-safe."""

    def __init__(self, names: list[str]) -> None:
        self._lock = threading.Lock()
        self.total = dict.fromkeys(names, 0)
        self.counted = dict.fromkeys(names, 0)
        self.latencies_ns: list[int] = []
        self.seqs: dict[str, list[int]] = {n: [] for n in names}
        self.marked = False

    def add(self, name: str, latency_ns: int, seq: int | None = None) -> None:
        with self._lock:
            self.total[name] += 1
            if self.marked:
                self.counted[name] += 1
                self.latencies_ns.append(latency_ns)
                if seq is not None:
                    self.seqs[name].append(seq)

    def mark(self) -> None:
        with self._lock:
            self.marked = True
            self._t0 = time.monotonic()

    def freeze(self) -> Delivery:
        with self._lock:
            self.marked = False
            return Delivery(
                time.monotonic() - self._t0,
                dict(self.counted),
                list(self.latencies_ns),
                {n: list(s) for n, s in self.seqs.items()},
            )


@dataclass
class Delivery:
    seconds: float  # from mark() to freeze()
    per_subscriber: dict[str, int]
    latencies_ns: list[int]
    seqs: dict[str, list[int]] = field(default_factory=dict)

    def latency_ms(self, q: float) -> float:
        if not self.latencies_ns:
            return float("nan")
        xs = sorted(self.latencies_ns)
        return xs[min(len(xs) - 1, int(q * len(xs)))] / 1e6

    @property
    def values_per_s(self) -> float:
        return sum(self.per_subscriber.values()) / self.seconds

    @property
    def median_ms(self) -> float:
        return statistics.median(self.latencies_ns) / 1e6 if self.latencies_ns else float("nan")


class System(Protocol):
    name: str
    link_port: int
    broker_pid: int
    tally: Tally

    def stop(self) -> dict[str, Any]: ...


def wait_all_delivered(tally: Tally, procs: list[Proc], timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if all(tally.total.values()):
            return
        for p in procs:
            if not p.alive():
                raise RuntimeError(f"{p.name} exited:\n{p.log()[-2000:]}")
        time.sleep(0.05)
    missing = [n for n, c in tally.total.items() if not c]
    raise RuntimeError(f"no value within {timeout_s} s for {missing}")


def _last_json(proc: Proc) -> dict[str, Any]:
    lines = [ln for ln in proc.log().splitlines() if ln.startswith("{")]
    return dict(json.loads(lines[-1])) if lines else {}


class ModdLink:
    name = "MoDD link"

    def __init__(self, tmp: Path, sc: Scenario, seconds: float) -> None:
        import modd
        from modd.zenoh_session import client_settings, open_session

        self.link_port, ingress, zport = free_port(), free_port(), free_port()
        model = model_copy(tmp, sc.path.name)
        self.tally = Tally([s.name for s in sc.subscriptions])
        self.pb = start_pubbroker(tmp, model, self.link_port, ingress)
        self.sb = start_subbroker(tmp, subbroker_config(tmp, model, self.link_port, zport))
        self.procs = [self.pb, self.sb]
        try:
            wait_port(zport, 15)
            viewer = shared_credentials().cred_file("viewer")  # the SubBroker authenticates
            self.session = open_session(client_settings(f"tcp/127.0.0.1:{zport}", viewer))
            self.subs = [
                modd.subscribe(sc.drone, s.name, self._receiver(s.name), session=self.session)
                for s in sc.subscriptions
            ]
            self.load = start_load(tmp, model, ingress, seconds + 30)
            self.procs.append(self.load)
            slowest = max(float(s.period_s) for s in sc.subscriptions)
            wait_all_delivered(self.tally, self.procs, 15 + 2 * slowest)
        except BaseException:
            self.stop()
            raise
        self.broker_pid = self.pb.pid

    def _receiver(self, name: str) -> Any:
        def on_value(v: Any) -> None:  # window end (drone clock) -> receipt (same host)
            self.tally.add(name, time.time_ns() - v.end_ns)

        return on_value

    def stop(self) -> dict[str, Any]:
        for sub in getattr(self, "subs", []):
            sub.close()
        if hasattr(self, "session"):
            self.session.close()  # type: ignore[no-untyped-call]
        for p in reversed(self.procs):
            p.stop()
        return {"pubbroker_log": self.pb.log()[-500:]}


class MosquittoLink:
    name = "Mosquitto"

    def __init__(self, tmp: Path, sc: Scenario, seconds: float) -> None:
        import paho.mqtt.client as mqtt
        from paho.mqtt.enums import CallbackAPIVersion

        self.broker = Mosquitto(tmp)
        self.link_port, self.broker_pid = self.broker.link_port, self.broker.pid
        self.tally = Tally([s.name for s in sc.subscriptions])
        self.clients: list[Any] = []
        self.procs = [self.broker.proc]
        try:
            for s in sc.subscriptions:
                c = mqtt.Client(CallbackAPIVersion.VERSION2, client_id=f"base-{s.name}")
                c.on_message = self._receiver(s.name)
                subscribed = threading.Event()
                c.on_subscribe = lambda *a, ev=subscribed: ev.set()
                c.connect("127.0.0.1", self.link_port, keepalive=60)
                c.loop_start()
                c.subscribe(mqtt_topic(s.topic), qos=0)
                self.clients.append(c)
                if not subscribed.wait(10):
                    raise RuntimeError(f"{s.name}: no SUBACK from Mosquitto")
            load = json.dumps([[float(p), [mqtt_topic(t) for t in ts]] for p, ts in sc.publishers])
            self.pub = Proc(
                "mqtt-publisher",
                [
                    PYTHON,
                    str(HERE / "mqtt_publisher.py"),
                    "--port",
                    str(self.broker.drone_port),
                    "--load",
                    load,
                    "--seconds",
                    str(seconds + 30),
                ],
                tmp / "mqtt-publisher.log",
            )
            self.procs.append(self.pub)
            wait_all_delivered(self.tally, self.procs, 15)
        except BaseException:
            self.stop()
            raise

    def _receiver(self, name: str) -> Any:
        def on_message(client: Any, userdata: Any, msg: Any) -> None:
            sent_ns, _, seq = PAYLOAD.unpack(msg.payload)
            self.tally.add(name, time.time_ns() - sent_ns, seq)

        return on_message

    def stop(self) -> dict[str, Any]:
        sent: dict[str, Any] = {}
        if hasattr(self, "pub"):
            self.pub.stop()
            sent = _last_json(self.pub).get("sent", {})
            time.sleep(0.3)  # the last messages reach the subscribers
        for c in self.clients:
            c.disconnect()
            c.loop_stop()
        self.broker.stop()
        return {"sent": sent, "received": dict(self.tally.total)}


class ZenohLink:
    name = "zenoh downsampling"

    def __init__(self, tmp: Path, sc: Scenario, seconds: float) -> None:
        from modd.zenoh_session import ZenohSettings, open_session

        self.link_port = free_port()
        self.tally = Tally([s.name for s in sc.subscriptions])
        keys: list[tuple[str, str, float]] = [
            (f"bench/{sc.drone}/sub/{s.name}", s.topic, 1 / float(s.period_s))
            for s in sc.subscriptions
        ]
        plan = {"publishers": [[float(p), ts] for p, ts in sc.publishers], "keys": keys}
        self.drone = Proc(
            "zenoh-drone",
            [
                PYTHON,
                str(HERE / "zenoh_drone.py"),
                "--listen",
                f"tcp/127.0.0.1:{self.link_port}",
                "--plan",
                json.dumps(plan),
                "--seconds",
                str(seconds + 30),
            ],
            tmp / "zenoh-drone.log",
        )
        self.broker_pid = self.drone.pid
        try:
            if not self.drone.wait_log("ready", 15):
                raise RuntimeError(f"zenoh drone did not start: {self.drone.log()}")
            # a peer of the drone-side router, as measured before (docs/benchmarks.md)
            self.session = open_session(
                ZenohSettings(mode="peer", connect=(f"tcp/127.0.0.1:{self.link_port}",))
            )
            self.subs = [
                self.session.declare_subscriber(k, self._receiver(s.name))
                for (k, _, _), s in zip(keys, sc.subscriptions, strict=True)
            ]
            slowest = max(float(s.period_s) for s in sc.subscriptions)
            wait_all_delivered(self.tally, [self.drone], 15 + 2 * slowest)
        except BaseException:
            self.stop()
            raise

    def _receiver(self, name: str) -> Any:
        def on_sample(sample: Any) -> None:
            sent_ns, _, seq = PAYLOAD.unpack(sample.payload.to_bytes())
            self.tally.add(name, time.time_ns() - sent_ns, seq)

        return on_sample

    def stop(self) -> dict[str, Any]:
        for sub in getattr(self, "subs", []):
            sub.undeclare()
        if hasattr(self, "session"):
            self.session.close()  # type: ignore[no-untyped-call]
        self.drone.stop()
        return {"sent": _last_json(self.drone).get("sent", 0)}


SYSTEMS: dict[str, type[ModdLink] | type[MosquittoLink] | type[ZenohLink]] = {
    "modd": ModdLink,
    "mosquitto": MosquittoLink,
    "zenoh": ZenohLink,
}
