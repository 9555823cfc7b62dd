"""A real base station on loopback for the backend's live tests: the C++
PubBroker (build/bin/modd-pubbroker), the SubBroker CLI (modd-subbroker) and
a publisher thread speaking the PubBroker's ingress protocol (docs/ingress.md).
Processes are stopped by their PID (SIGTERM, then SIGKILL after a bound)."""

from __future__ import annotations

import contextlib
import json
import os
import random
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from modd.ports import free_port
from modd.zenoh_auth import CredentialStore

REPO = Path(__file__).resolve().parents[2]
PUBBROKER = REPO / "build" / "bin" / "modd-pubbroker"
KEY = "modd-backend-test-key"


def wait_port(port: int, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
            return
        time.sleep(0.02)
    raise TimeoutError(f"nothing listens on 127.0.0.1:{port}")


class Proc:
    """A child process logging to a file; stopped by PID."""

    def __init__(self, cmd: list[str], log: Path) -> None:
        self.log_path = log
        with log.open("ab") as out:
            env = {**os.environ, "MODD_LINK_KEY": KEY}
            self.p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, env=env)

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait_log(self, text: str, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and self.p.poll() is None:
            if text in self.log():
                return True
            time.sleep(0.05)
        return text in self.log()

    def stop(self) -> None:
        if self.p.poll() is None:
            os.kill(self.p.pid, signal.SIGTERM)
            try:
                self.p.wait(10)
            except subprocess.TimeoutExpired:
                os.kill(self.p.pid, signal.SIGKILL)
                self.p.wait(5)


def _varint(v: int) -> bytes:
    out = bytearray()
    while True:
        b, v = v & 0x7F, v >> 7
        out.append(b | 0x80 if v else b)
        if not v:
            return bytes(out)


def _string(s: str) -> bytes:
    data = s.encode()
    return _varint(len(data)) + data


def _frame(mtype: int, body: bytes) -> bytes:
    return _varint(len(body) + 1) + bytes([mtype]) + body


TYPES = {"float32": (0, "<f"), "float64": (1, "<d"), "int": (2, "<q"), "bool": (3, "<B")}
# An instrument's health as modd-sensors reports it (docs/ingress.md, HEALTH; fields in
# docs/protocol.md's order): the PubBroker forwards it in STATUS, the SubBroker puts it in
# its status document's `sensors`.
HEALTH = {
    "ctd": {
        "state": 1,
        "lines_ok": 120,
        "lines_bad": 3,
        "reconnects": 2,
        "last_value_ms": 1_700_000_000_123,
    }
}


def _sample(topic: str, i: int, rng: random.Random) -> float:
    """A survey track for position variables (moving north-east from 43N 5E),
    small angles for attitude, noise in [-9, 9] for everything else."""
    variable = topic.rsplit(".", 1)[-1]
    if variable == "latitude":
        return 43.0 + 2e-5 * i
    if variable == "longitude":
        return 5.0 + 3e-5 * i
    if variable in ("roll", "pitch", "yaw"):
        return rng.uniform(-0.2, 0.2)
    return rng.uniform(-9, 9)


class Publisher(threading.Thread):
    """Publishes every topic of every publisher of the model at its period
    (HELLO, topic declarations, then one batch of records per period)."""

    def __init__(self, model: dict[str, Any], port: int) -> None:
        super().__init__(daemon=True)
        self.model, self.port = model, port
        self.stop_event = threading.Event()
        drone = model["drone"]["name"]
        self.types = {
            f"{drone}.{s['name']}.{v['name']}": v.get("type", "float32")
            for s in model["drone"]["sensors"]
            for v in s["variables"]
        }

    def run(self) -> None:
        rng = random.Random(7)
        pubs = self.model["publishers"]
        with socket.create_connection(("127.0.0.1", self.port)) as sock:
            sock.sendall(_frame(0x01, bytes([1]) + _string("backend-test")))
            ids: dict[str, int] = {}
            for pub in pubs:
                for topic in pub["topics"]:
                    if topic not in ids:
                        ids[topic] = len(ids)
                        code = TYPES[self.types[topic]][0]
                        sock.sendall(
                            _frame(0x02, _varint(ids[topic]) + bytes([code]) + _string(topic))
                        )
            sock.sendall(
                _frame(
                    0x04,
                    _varint(len(HEALTH))
                    + b"".join(
                        _string(name) + _varint(len(h)) + b"".join(_varint(v) for v in h.values())
                        for name, h in HEALTH.items()
                    ),
                )
            )
            start = time.monotonic()
            due = [start + float(p["periodS"]) for p in pubs]
            count = [0] * len(pubs)
            while not self.stop_event.is_set():
                k = min(range(len(pubs)), key=lambda j: due[j])
                self.stop_event.wait(max(0.0, due[k] - time.monotonic()))
                now = time.time_ns()
                records = b"".join(
                    _varint(ids[t])
                    + struct.pack("<q", now)
                    + struct.pack(TYPES[self.types[t]][1], _sample(t, count[k], rng))
                    for t in pubs[k]["topics"]
                )
                sock.sendall(_frame(0x03, _varint(len(pubs[k]["topics"])) + records))
                count[k] += 1
                due[k] += float(pubs[k]["periodS"])


class Station:
    """PubBroker + SubBroker + publisher for one model (its drone's name)."""

    def __init__(self, tmp: Path, model: dict[str, Any]) -> None:
        self.tmp, self.model = tmp, model
        for sub in model["subscribers"]:
            sub.pop("endpoint", None)  # zenoh delivery only: fixed ports may be taken
        self.model_path = tmp / "model.json"
        self.model_path.write_text(json.dumps(model))
        self.link, self.ingress, zport = free_port(), free_port(), free_port()
        self.zenoh = f"tcp/127.0.0.1:{zport}"
        self.archive = tmp / "archive" / model["drone"]["name"]
        self.procs: list[Proc] = []
        self.publisher: Publisher | None = None
        #: the SubBroker's zenoh credentials and deploy key (docs/security.md)
        self.credentials = CredentialStore(tmp / "credentials").ensure()

    def start(self) -> None:
        if not PUBBROKER.exists():
            raise FileNotFoundError(f"{PUBBROKER} is missing: run `make build` first")
        cfg = {
            "name": self.model["drone"]["name"],
            "link": {"host": "127.0.0.1", "port": self.link, "key": "env:MODD_LINK_KEY"},
            "ingress": {"host": "127.0.0.1", "port": self.ingress},
            "archive": {"dir": str(self.archive), "flush_interval_ms": 200},
            "topics": [
                {
                    "name": f"{self.model['drone']['name']}.{s['name']}.{v['name']}",
                    "type": v.get("type", "float32"),
                }
                for s in self.model["drone"]["sensors"]
                for v in s["variables"]
            ],
            "status_period_s": 60,
        }
        (self.tmp / "pb.json").write_text(json.dumps(cfg))
        self.procs.append(
            Proc([str(PUBBROKER), "--config", str(self.tmp / "pb.json")], self.tmp / "pb.log")
        )
        wait_port(self.link)
        (self.tmp / "sb.toml").write_text(
            f"model = {json.dumps(str(self.model_path))}\n[link]\n"
            f'endpoint = "127.0.0.1:{self.link}"\nkey = "env:MODD_LINK_KEY"\n'
            "pubbroker_status_period_s = 1\n"  # the PubBroker's STATUS (and HEALTH) every second
            f'[zenoh]\nlisten = ["{self.zenoh}"]\n'
            f"credentials_dir = {json.dumps(str(self.credentials.dir))}\n[delivery]\ntcp = false\n"
            f"status_period_s = 0.5\n"
        )
        sb = Proc(
            [sys.executable, "-m", "modd.subbroker.cli", "--config", str(self.tmp / "sb.toml")],
            self.tmp / "sb.log",
        )
        self.procs.append(sb)
        if not sb.wait_log("running", 30):
            raise RuntimeError("the SubBroker did not start a config:\n" + sb.log())
        self.publisher = Publisher(self.model, self.ingress)
        self.publisher.start()

    def stop(self) -> None:
        if self.publisher is not None:
            self.publisher.stop_event.set()
            self.publisher.join(5)
        for p in reversed(self.procs):
            p.stop()
