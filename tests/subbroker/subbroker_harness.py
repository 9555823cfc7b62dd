"""Real processes on loopback for the SubBroker's end-to-end tests and the
link benchmark: the C++ PubBroker (build/bin/modd-pubbroker), the SubBroker
CLI, the publisher load; a blackhole-able TCP proxy; the MCAP oracle.

Every process is stopped by its PID (SIGTERM, then SIGKILL after a bound).
"""

from __future__ import annotations

import bisect
import contextlib
import functools
import json
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from modd.ports import free_port as free_port  # re-exported: the tests import it from here
from modd.zenoh_auth import CredentialStore
from modd_model import load_model
from modd_model.query import topics
from modd_plan.derive import aggregate

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO / "metamodel" / "examples" / "scenarios"  # the paper's reference scenarios
PUBBROKER = REPO / "build" / "bin" / "modd-pubbroker"
PYTHON = Path(sys.executable)
SUBBROKER = [str(PYTHON), "-m", "modd.subbroker.cli"]
LOADGEN = [str(PYTHON), str(Path(__file__).with_name("loadgen.py"))]
KEY = "modd-test-link-key-16"


@functools.cache
def shared_credentials() -> CredentialStore:
    """The zenoh credentials (and deploy key) every SubBroker and client of
    this test process uses: made once, in a private temporary directory."""
    return CredentialStore(Path(tempfile.mkdtemp(prefix="modd-zcred-")) / "credentials").ensure()


def signed(request_body: dict[str, Any]) -> dict[str, Any]:
    """A deploy request signed as the workbench signs it."""
    from modd_model.signing import sign_request

    return sign_request(shared_credentials().deploy_key(), request_body)


class Proc:
    """A child process with its log file; stopped by PID."""

    def __init__(
        self,
        name: str,
        cmd: list[str],
        log: Path,
        env: dict[str, str] | None = None,
        dumps_stacks: bool = False,
    ):
        self.name, self.cmd, self.log_path = name, cmd, log
        # SIGUSR1 prints the threads' stacks into the log (modd-subbroker only)
        self.dumps_stacks = dumps_stacks
        self._log = open(log, "ab")  # noqa: SIM115 - closed in stop()
        full_env = {**os.environ, "MODD_LINK_KEY": KEY, **(env or {})}
        self.p = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT, env=full_env)
        self.started = time.monotonic()

    @property
    def pid(self) -> int:
        return self.p.pid

    def alive(self) -> bool:
        return self.p.poll() is None

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def wait_log(self, text: str, timeout_s: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if text in self.log():
                return True
            if not self.alive():
                return text in self.log()
            time.sleep(0.02)
        if self.dumps_stacks and self.alive():  # the failure's message shows what it waited on
            os.kill(self.pid, signal.SIGUSR1)
            time.sleep(0.5)
        return False

    def stop(self, timeout_s: float = 10.0) -> int | None:
        if self.alive():
            os.kill(self.pid, signal.SIGTERM)
            try:
                self.p.wait(timeout_s)
            except subprocess.TimeoutExpired:
                os.kill(self.pid, signal.SIGKILL)
                self.p.wait(5)
        self._log.close()
        return self.p.returncode

    def kill9(self) -> None:
        if self.alive():
            os.kill(self.pid, signal.SIGKILL)
            self.p.wait(5)
        self._log.close()


def wait_port(port: int, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
            return
        time.sleep(0.02)
    raise TimeoutError(f"nothing listens on 127.0.0.1:{port}")


def model_copy(tmp: Path, scenario: str, tcp_ports: dict[str, int] | None = None) -> Path:
    """A copy of a scenario as JSON, with the given subscribers' TCP endpoints
    moved to free ports and the others' removed (the scenario's fixed ports
    may be taken on a shared machine)."""
    model = load_model(SCENARIOS / scenario)
    for sub in model["subscribers"]:
        port = (tcp_ports or {}).get(sub["name"])
        if port:
            sub["endpoint"] = {"host": "127.0.0.1", "port": port}
        else:
            sub.pop("endpoint", None)
    path = tmp / scenario.replace(".modd", ".json")
    path.write_text(json.dumps(model))
    return path


def start_pubbroker(
    tmp: Path,
    model_path: Path,
    link_port: int,
    ingress_port: int,
    tag: str = "pb",
    command: list[str] | None = None,
    **extra: Any,
) -> Proc:
    model = load_model(model_path)
    cfg = {
        "name": model["drone"]["name"],
        "link": {"host": "127.0.0.1", "port": link_port, "key": "env:MODD_LINK_KEY"},
        "ingress": {"host": "127.0.0.1", "port": ingress_port},
        "archive": {"dir": str(tmp / "archive"), "flush_interval_ms": 200},
        "topics": [{"name": t.name, "type": t.type} for t in topics(model).values()],
        "status_period_s": 60,
    }
    cfg.update(extra)
    path = tmp / f"{tag}.json"
    path.write_text(json.dumps(cfg))
    # command: another build, e.g. the arm64 one under qemu (test_arm64_link.py)
    proc = Proc(tag, [*(command or [str(PUBBROKER)]), "--config", str(path)], tmp / f"{tag}.log")
    wait_port(link_port, 30.0 if command else 10.0)
    return proc


def subbroker_config(
    tmp: Path,
    model_path: Path,
    link_port: int | str,
    zenoh_port: int,
    tcp: bool = False,
    tag: str = "sb",
    state_dir: Path | None = None,
    **link: Any,
) -> Path:
    # link_port: the PubBroker's port on 127.0.0.1, or the whole endpoint (host:port)
    endpoint = link_port if isinstance(link_port, str) else f"127.0.0.1:{link_port}"
    link_lines = "\n".join(f"{k} = {json.dumps(v)}" for k, v in link.items())
    state = f"state_dir = {json.dumps(str(state_dir))}" if state_dir else ""
    path = tmp / f"{tag}.toml"
    path.write_text(f"""
model = {json.dumps(str(model_path))}
{state}
[link]
endpoint = "{endpoint}"
key = "env:MODD_LINK_KEY"
{link_lines}
[zenoh]
listen = ["tcp/127.0.0.1:{zenoh_port}"]
credentials_dir = {json.dumps(str(shared_credentials().dir))}
[delivery]
tcp = {"true" if tcp else "false"}
status_period_s = 0.5
""")
    return path


def start_subbroker(tmp: Path, config: Path, tag: str = "sb") -> Proc:
    return Proc(tag, [*SUBBROKER, "--config", str(config)], tmp / f"{tag}.log", dumps_stacks=True)


def start_load(
    tmp: Path,
    model_path: Path,
    ingress_port: int,
    seconds: float,
    tag: str = "load",
    seed: int = 1,
    record: Path | None = None,
    signal: str = "uniform",
) -> Proc:
    extra = (["--record", str(record)] if record else []) + ["--signal", signal]
    return Proc(
        tag,
        [
            *LOADGEN,
            "--model",
            str(model_path),
            "--ingress",
            f"127.0.0.1:{ingress_port}",
            "--seconds",
            str(seconds),
            "--seed",
            str(seed),
            *extra,
        ],
        tmp / f"{tag}.log",
    )


def load_counts(proc: Proc) -> dict[str, int]:
    """Samples the load sent per topic (its last stdout line)."""
    lines = [ln for ln in proc.log().splitlines() if ln.startswith("{")]
    return dict(json.loads(lines[-1])["sent"]) if lines else {}


# -- the oracle ------------------------------------------------------------------


def f32(x: float) -> float:
    return float(struct.unpack("<f", struct.pack("<f", x))[0])


Archive = dict[str, list[tuple[int, Any]]]


def read_archive(
    directory: Path, model_path: Path | None = None, published: bool = False
) -> Archive:
    """Every sample of every MCAP file, per topic: (log_time ns, value), in
    time order. Read with the official reader's stream API, which stops at a
    truncated tail (a PubBroker killed with -9) instead of failing. With the
    model, float32 values are read back as float32 (the archive writes their
    shortest decimal form). ``published``: the publisher's timestamps instead
    of the PubBroker's log times."""
    f32_topics = set()
    if model_path is not None:
        f32_topics = {
            t.name for t in topics(load_model(model_path)).values() if t.type == "float32"
        }
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    out: dict[str, list[tuple[int, Any]]] = {}
    for path in sorted(directory.glob("*.mcap")):
        channels: dict[int, str] = {}
        with open(path, "rb") as f:
            try:
                for rec in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                    if isinstance(rec, Channel):
                        channels[rec.id] = rec.topic
                    elif isinstance(rec, Message):
                        topic = channels[rec.channel_id]
                        value = json.loads(rec.data)["value"]
                        if topic in f32_topics:
                            value = f32(value)
                        t = rec.publish_time if published else rec.log_time
                        out.setdefault(topic, []).append((t, value))
            except Exception:  # a truncated tail: everything before it counts
                pass
    for samples in out.values():
        samples.sort(key=lambda s: s[0])
    return out


def window_samples(samples: list[tuple[int, Any]], start_ns: int, end_ns: int) -> list[Any]:
    """Samples stamped in [start, end): the PubBroker's window rule. ``samples``
    sorted by time, as read_archive gives them: a bisection, not a scan (an
    hour's soak checks 75,000 windows against 270,000 samples)."""
    lo = bisect.bisect_left(samples, start_ns, key=_stamp)
    hi = bisect.bisect_left(samples, end_ns, lo, key=_stamp)
    return [v for _, v in samples[lo:hi]]


def _stamp(sample: tuple[int, Any]) -> int:
    return sample[0]


def oracle_value(aggregation: str, samples: list[Any]) -> tuple[Any, int | None]:
    """(value, count) as a delivered value carries them, from raw samples."""
    w = aggregate(aggregation, samples)
    if aggregation == "AVERAGE":
        return (None, 0) if w is None else (w[0], w[1])
    if aggregation in ("COUNT",):
        return w, w
    if aggregation == "ALL":
        return w, len(w)
    if aggregation == "SUM" and not samples:
        return None, None
    return w, None


def close_enough(aggregation: str, got: Any, want: Any) -> bool:
    if got is None or want is None:
        return got is None and want is None
    if aggregation in ("AVERAGE", "SUM"):
        return bool(abs(got - want) <= 1e-5 * max(1.0, abs(want)))
    return bool(got == want)


def check_against_archive(values: dict[str, list[Any]], archive: Archive) -> int:
    """Every delivered window equals the archive's; returns how many were checked."""
    checked = 0
    for name, vals in values.items():
        for v in vals:
            samples = window_samples(archive.get(v.topic, []), v.start_ns, v.end_ns)
            want, want_count = oracle_value(v.aggregation, samples)
            assert close_enough(v.aggregation, v.value, want), (name, v, want, len(samples))
            if v.aggregation in ("AVERAGE", "COUNT", "ALL"):
                assert v.count == want_count, (name, v, want_count)
            checked += 1
    return checked


def assert_contiguous(vals: list[Any], period_ns: int) -> None:
    ends = [v.end_ns for v in vals]
    assert ends == sorted(ends)
    gaps = [b - a for a, b in zip(ends, ends[1:], strict=False) if b - a != period_ns]
    assert not gaps, f"missing windows: gaps {gaps[:5]} (period {period_ns})"


# -- a proxy that can drop the traffic -------------------------------------------------


class Blackhole:
    """A TCP proxy 127.0.0.1:port -> 127.0.0.1:target. ``drop()`` stops
    forwarding in both directions without closing anything (packets lost on
    a dead radio); ``restore()`` closes what was open during the drop (the
    peers would find those connections dead) and forwards again."""

    def __init__(self, target: int) -> None:
        self.target = target
        self.port = free_port()
        self.dropping = False
        self.forwarded = [0, 0]  # bytes up (to target), down
        self._pairs: list[tuple[socket.socket, socket.socket]] = []
        self._lock = threading.Lock()
        self._server = socket.create_server(("127.0.0.1", self.port))
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def drop(self) -> None:
        self.dropping = True

    def restore(self) -> None:
        with self._lock:
            pairs, self._pairs = self._pairs, []
        for a, b in pairs:
            a.close()
            b.close()
        self.dropping = False

    def close(self) -> None:
        self._stop = True
        self.restore()
        self._server.close()
        self._thread.join(timeout=2)

    def _run(self) -> None:
        while not self._stop:
            with self._lock:
                socks = [s for pair in self._pairs for s in pair]
            try:
                ready, _, _ = select.select([self._server, *socks], [], [], 0.05)
            except (OSError, ValueError):
                continue
            for s in ready:
                if s is self._server:
                    self._accept()
                elif not self.dropping:
                    self._forward(s)

    def _accept(self) -> None:
        try:
            client, _ = self._server.accept()
        except OSError:
            return
        if self.dropping:
            with self._lock:  # a connection attempt into the void: kept, never answered
                self._pairs.append((client, socket.socket()))
            return
        try:
            upstream = socket.create_connection(("127.0.0.1", self.target), 1.0)
        except OSError:
            client.close()
            return
        with self._lock:
            self._pairs.append((client, upstream))

    def _forward(self, s: socket.socket) -> None:
        with self._lock:
            pair = next((p for p in self._pairs if s in p), None)
        if pair is None:
            return
        other = pair[1] if s is pair[0] else pair[0]
        try:
            data = s.recv(65536)
            if data:
                other.sendall(data)
                self.forwarded[0 if s is pair[0] else 1] += len(data)
                return
        except OSError:
            pass
        with self._lock:
            if pair in self._pairs:
                self._pairs.remove(pair)
        pair[0].close()
        pair[1].close()


@contextlib.contextmanager
def processes(*procs: Proc | None) -> Iterator[None]:
    """Stop the processes on exit, last first (None: one that never started)."""
    try:
        yield
    finally:
        for p in reversed(procs):
            if p is not None:
                p.stop()


@dataclass
class Scenario1:
    """Scenario 1 on loopback: the PubBroker, the SubBroker (``sb`` may be replaced by
    a restarted one: the one there at the end is stopped) and the load generator."""

    model: Path
    config: Path
    port: int  # the SubBroker's zenoh port
    pb: Proc
    sb: Proc
    load: Proc | None = None


@contextlib.contextmanager
def scenario1_running(tmp: Path, load_s: float, config_extra: str = "") -> Iterator[Scenario1]:
    """Scenario 1's processes on free ports under ``tmp``, once the SubBroker runs
    its first config; ``config_extra`` is appended to its config (TOML tables).
    All stopped on exit, last first."""
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp, "scenario1.modd")
    config = subbroker_config(tmp, model, link, zport)
    config.write_text(config.read_text() + config_extra)
    pb = start_pubbroker(tmp, model, link, ingress)
    s = Scenario1(model, config, zport, pb, start_subbroker(tmp, config))
    try:
        s.load = start_load(tmp, model, ingress, load_s)
        wait_port(zport)
        assert s.sb.wait_log("config 1 running", 15), s.sb.log()
        yield s
    finally:
        with processes(s.pb, s.sb, s.load):
            pass
