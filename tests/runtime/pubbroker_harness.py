"""Drives the real modd-pubbroker binary in tests and benchmarks: config files, the process,
a base station speaking the link protocol with the Python codec, publisher loads, the MCAP
archive read with the official `mcap` reader, and the window oracle.

Everything runs on 127.0.0.1 with free ports and temporary directories; processes are
stopped by PID.
"""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import struct
import subprocess
import threading
import time
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from modd.link import codec
from modd.link.auth import client_handshake, read_frame
from modd.link.frames import (
    Aggregation,
    AuthOk,
    Config,
    ConfigAck,
    ErrorMsg,
    Ping,
    Pong,
    Status,
    StreamSpec,
    TopicSpec,
    ValueType,
)
from modd.link.receiver import Receiver, Window
from modd.ports import free_port
from modd.publisher import Publisher

REPO = Path(__file__).resolve().parents[2]
BIN = REPO / "build" / "bin" / "modd-pubbroker"
SCENARIOS = REPO / "metamodel" / "examples" / "scenarios"
KEY = b"pubbroker-test-key"


def f32(x: float) -> float:
    return float(struct.unpack("<f", struct.pack("<f", x))[0])


class PubBroker:
    """The binary with a config of its own; stop() sends SIGTERM and waits."""

    def __init__(self, tmp: Path, topics: Sequence[tuple[str, str]] = (), **overrides: Any) -> None:
        self.tmp = tmp
        self.link_port = free_port()
        self.tcp_port = free_port()
        self.unix_path = str(tmp / "ingress.sock")
        self.archive_dir = tmp / "archive"
        (tmp / "key").write_bytes(KEY + b"\n")
        self.config: dict[str, Any] = {
            "name": "usv",
            "link": {
                "host": "127.0.0.1",
                "port": self.link_port,
                "key": f"file:{tmp / 'key'}",
                "handshake_timeout_ms": 2000,
            },
            "ingress": {"unix_path": self.unix_path, "host": "127.0.0.1", "port": self.tcp_port},
            "archive": {
                "dir": str(self.archive_dir),
                "prefix": "usv",
                "flush_interval_ms": 200,
                "fsync": "never",
            },
            "topics": [{"name": n, "type": t} for n, t in topics],
            "default_buffer_size": 25,
            "status_period_s": 1,
            "log_period_s": 1,
        }
        for k, v in overrides.items():
            if isinstance(v, dict) and isinstance(self.config.get(k), dict):
                self.config[k].update(v)
            else:
                self.config[k] = v
        self.config_path = tmp / "pubbroker.json"
        self.config_path.write_text(json.dumps(self.config, indent=1))
        self.log_path = tmp / "pubbroker.log"
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> PubBroker:
        if not BIN.exists():
            raise RuntimeError(f"{BIN} is missing: run `make build` first")
        self._log = open(self.log_path, "wb")  # noqa: SIM115 (closed in stop)
        self.proc = subprocess.Popen(
            [str(BIN), "--config", str(self.config_path)],
            stdout=self._log,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"modd-pubbroker exited: {self.log()}")
            try:
                socket.create_connection(("127.0.0.1", self.link_port), timeout=0.2).close()
                if os.path.exists(self.unix_path):
                    return self
            except OSError:
                pass
            time.sleep(0.02)
        raise RuntimeError("modd-pubbroker did not start listening")

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 10.0) -> int:
        if self.proc is None:
            return 0
        try:
            if self.proc.poll() is None:
                self.proc.send_signal(sig)
                try:
                    self.proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait(5)
            return int(self.proc.returncode)
        finally:
            self._log.close()

    def __enter__(self) -> PubBroker:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


@dataclass
class Received:
    windows: list[Window] = field(default_factory=list)
    statuses: list[dict[str, int]] = field(default_factory=list)
    acks: list[ConfigAck] = field(default_factory=list)
    pongs: list[bytes] = field(default_factory=list)
    errors: list[ErrorMsg] = field(default_factory=list)
    data_frames: int = 0
    data_bytes: int = 0
    sensors: dict[str, dict[str, int]] = field(default_factory=dict)  # last STATUS's instruments


class BaseStation:
    """The SubBroker's side of the link, with the Python codec."""

    def __init__(self, port: int, key: bytes = KEY) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.auth_ok: AuthOk
        try:
            self.auth_ok, self.splitter = client_handshake(self.sock, key)
        except BaseException:
            self.sock.close()
            raise
        self.rx = Receiver()
        self._sent: dict[int, Config] = {}
        self.got = Received()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def configure(self, config: Config, timeout: float = 5.0) -> ConfigAck:
        with self._lock:
            n = len(self.got.acks)
            # Registered by the reader when the ACK arrives, before any later DATA frame:
            # the new config's first (sync) frame may follow the ACK by a millisecond.
            self._sent[config.config_id] = config
        self.sock.sendall(codec.encode(config))
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self._thread is None:
                self._handle(read_frame(self.sock, self.splitter))
            with self._lock:
                if len(self.got.acks) > n:
                    return self.got.acks[n]
            if self._thread is not None:
                time.sleep(0.005)
        raise TimeoutError("no CONFIG_ACK")

    def resume(self, config: Config) -> None:
        """After a reconnection: the broker still runs `config` (AUTH_OK says which)."""
        assert self.auth_ok.config_id == config.config_id
        self.rx.add_config(config, self.auth_ok.epoch_ns)

    def _handle(self, f: codec.RawFrame) -> None:
        with self._lock:
            if codec.is_data_type(f.type):
                self.got.windows += self.rx.on_frame(f)
                self.got.data_frames += 1
                self.got.data_bytes += f.size
                return
            m = codec.decode(f)
            if isinstance(m, Status):
                self.got.statuses.append(m.as_dict())
                self.got.sensors = {h.name: h.as_dict() for h in m.sensors}
            elif isinstance(m, ConfigAck):
                self.got.acks.append(m)
                if m.status == 0 and m.config_id in self._sent:
                    self.rx.add_config(self._sent[m.config_id], m.epoch_ns)
            elif isinstance(m, Pong):
                self.got.pongs.append(m.payload)
            elif isinstance(m, ErrorMsg):
                self.got.errors.append(m)

    def ping(self, payload: bytes) -> None:
        self.sock.sendall(codec.encode(Ping(payload)))

    def start(self) -> BaseStation:
        self.sock.settimeout(0.2)
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                return
            for f in self.splitter.feed(data):
                self._handle(f)

    def snapshot(self) -> Received:
        with self._lock:
            return Received(
                list(self.got.windows),
                list(self.got.statuses),
                list(self.got.acks),
                list(self.got.pongs),
                list(self.got.errors),
                self.got.data_frames,
                self.got.data_bytes,
                dict(self.got.sensors),
            )

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2)
        self.sock.close()


def scenario_config(n: int, config_id: int = 1, status_period_s: int = 1) -> Config:
    """CONFIG from the planner on the scenario file, as the SubBroker builds it."""
    from modd.subbroker.planning import config_for
    from modd_model import load_model
    from modd_plan import make_plan

    plan = make_plan(load_model(SCENARIOS / f"scenario{n}.modd"))
    return config_for(plan, config_id, status_period_s)


def hand_config_scenario1(config_id: int = 1, status_period_s: int = 1) -> Config:
    """Scenario 1 from the paper's numbers (buffer sizes 28, 28, 6; 4 streams sent)."""
    names = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
    topics = tuple(
        TopicSpec(n, ValueType.FLOAT32, b, 40000) for n, b in zip(names, (28, 28, 6), strict=True)
    )
    streams = (
        StreamSpec(0, Aggregation.AVERAGE, 250000),
        StreamSpec(1, Aggregation.AVERAGE, 250000),
        StreamSpec(2, Aggregation.MIN, 250000),
        StreamSpec(2, Aggregation.MAX, 250000),
    )
    return Config(config_id, status_period_s, topics, streams)


def signal_value(topic_index: int, k: int) -> float:
    """A deterministic, varied sensor value (float32-exact after the publisher's rounding)."""
    return f32(math.sin(0.37 * k + topic_index) * (3 + topic_index) + 0.01 * topic_index)


@dataclass
class LoadResult:
    published: int
    per_topic: dict[str, int]


def run_load(
    address: str,
    topics: Sequence[str],
    hz: float,
    seconds: float,
    value: Callable[[int, int], float] = signal_value,
    stop: threading.Event | None = None,
) -> LoadResult:
    """Publishes every topic at `hz` for `seconds`, paced on the wall clock (the paper's load)."""
    per_topic: dict[str, int] = defaultdict(int)
    with Publisher("pub_1", address) as pub:
        for t in topics:
            pub.declare(t, "float32")
        start = time.monotonic()
        k = 0
        while time.monotonic() - start < seconds and not (stop and stop.is_set()):
            due = start + k / hz
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            now = time.time_ns()
            for i, t in enumerate(topics):
                if pub.publish(t, now, value(i, k)):
                    per_topic[t] += 1
            k += 1
        assert pub.flush(5.0), "publisher could not hand everything over"
        st = pub.stats()
    assert st.dropped_queue_full == 0 and st.dropped_bad_topic == 0
    return LoadResult(sum(per_topic.values()), dict(per_topic))


@dataclass(frozen=True)
class Archived:
    log_time: int
    publish_time: int
    value: Any


def read_archive(directory: Path) -> dict[str, list[Archived]]:
    """Every message of every MCAP file, by topic, in log-time order, with the official reader."""
    out: dict[str, list[Archived]] = defaultdict(list)
    for path in sorted(directory.glob("*.mcap")):
        with open(path, "rb") as f:
            reader = make_reader(f)
            for _schema, channel, message in reader.iter_messages():
                value = json.loads(message.data)["value"]
                if channel.metadata.get("type") == "float32":
                    value = f32(value)  # JSON carries the shortest decimal of the float32
                out[channel.topic].append(Archived(message.log_time, message.publish_time, value))
    for v in out.values():
        v.sort(key=lambda a: a.log_time)
    return dict(out)


def recompute(agg: Aggregation, values: list[Any]) -> Any:
    if agg == Aggregation.MIN:
        return min(values)
    if agg == Aggregation.MAX:
        return max(values)
    if agg == Aggregation.FIRST:
        return values[0]
    if agg == Aggregation.LAST:
        return values[-1]
    if agg == Aggregation.COUNT:
        return len(values)
    if agg == Aggregation.SUM:
        return math.fsum(values)
    if agg == Aggregation.AVERAGE:
        return math.fsum(values) / len(values)
    return list(values)


def check_windows(
    windows: Sequence[Window], configs: dict[int, Config], archive: dict[str, list[Archived]]
) -> int:
    """The oracle: every received window equals the aggregate recomputed from the archive
    (exact for MIN/MAX/FIRST/LAST/COUNT, float32 tolerance for AVERAGE/SUM), and no window
    with archived samples is missing between the first and the last window received.
    Returns the number of windows checked."""
    import bisect

    seen: dict[tuple[int, int], set[int]] = defaultdict(set)
    for w in windows:
        cfg = configs[w.config_id]
        s = cfg.streams[w.stream]
        topic = cfg.topics[s.topic]
        samples = archive.get(topic.name, [])
        times = [a.log_time for a in samples]
        lo = bisect.bisect_left(times, w.start_ns)
        hi = bisect.bisect_left(times, w.end_ns)
        vals = [a.value for a in samples[lo:hi]]
        seen[(w.config_id, w.stream)].add(w.end_ns)
        if not w.value.present:
            assert not vals, f"window {w} absent but the archive has {len(vals)} samples in it"
            continue
        assert vals, f"window {w} present but the archive has no sample in it"
        want = recompute(s.aggregation, vals)
        v = w.value
        where = (
            f"config {w.config_id} stream {w.stream} ({topic.name} {s.aggregation.name})"
            f" slot {w.slot}"
        )
        if s.aggregation in (Aggregation.MIN, Aggregation.MAX, Aggregation.FIRST, Aggregation.LAST):
            got = v.number if topic.type in (ValueType.FLOAT32, ValueType.FLOAT64) else v.integer
            assert got == want, f"{where}: {got} != {want}"
        elif s.aggregation == Aggregation.COUNT:
            assert v.count == want, where
        elif s.aggregation == Aggregation.AVERAGE:
            assert v.count == len(vals), f"{where}: count {v.count} != {len(vals)}"
            assert math.isclose(v.number, want, rel_tol=1e-6, abs_tol=1e-6), (
                f"{where}: {v.number} != {want}"
            )
        elif s.aggregation == Aggregation.SUM:
            assert math.isclose(v.number or v.integer, want, rel_tol=1e-6, abs_tol=1e-5), where
        else:
            assert v.samples == vals, where
    # No missing window: for every stream, each window between its first and last received
    # one that holds archived samples was received.
    for (cid, sid), ends in seen.items():
        cfg = configs[cid]
        s = cfg.streams[sid]
        period = s.period_us * 1000
        times = [a.log_time for a in archive.get(cfg.topics[s.topic].name, [])]
        lo_end, hi_end = min(ends), max(ends)
        end = lo_end
        while end <= hi_end:
            i = bisect.bisect_left(times, end - period)
            j = bisect.bisect_left(times, end)
            if j > i:
                assert end in ends, f"config {cid} stream {sid}: window ending {end} missing"
            end += period
    return len(windows)


def read_archive_records(directory: Path) -> dict[str, list[Archived]]:
    """Like read_archive, for files a crash left without summary or footer: scans records
    with the official reader's stream reader, up to the last complete one."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    out: dict[str, list[Archived]] = defaultdict(list)
    for path in sorted(directory.glob("*.mcap")):
        channels: dict[int, Channel] = {}
        with open(path, "rb") as f:
            try:
                for rec in StreamReader(f).records:
                    if isinstance(rec, Channel):
                        channels[rec.id] = rec
                    elif isinstance(rec, Message):
                        ch = channels[rec.channel_id]
                        value = json.loads(rec.data)["value"]
                        if ch.metadata.get("type") == "float32":
                            value = f32(value)
                        out[ch.topic].append(Archived(rec.log_time, rec.publish_time, value))
            except (McapError, EOFError, struct.error):
                pass  # the torn tail of a killed file
    return dict(out)
