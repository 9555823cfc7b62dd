"""Real processes for the datagram transports (udp, serial): the PubBroker
with a udp or serial link, the SubBroker with the same, the radio emulator
(modd-radio: a UDP relay, or two pseudo-terminals), and an injecting relay
that forges and replays datagrams. Every process is stopped by its PID."""

from __future__ import annotations

import json
import os
import random
import re
import select
import socket
import subprocess
import sys
import threading
import time
from datetime import datetime
from pathlib import Path
from typing import Any

from modd.ports import free_port
from modd_model import load_model
from modd_model.query import topics
from subbroker_harness import (
    PUBBROKER,
    PYTHON,
    Proc,
    processes,
    shared_credentials,
    start_load,
    start_subbroker,
    subbroker_config,
    wait_port,
)

RADIO = [str(Path(sys.executable)), "-m", "modd.radio.cli"]
RADIO_300MS = "rate=3600,packet=252,latency_ms=300,seed=5"  # a SiK-like radio, 300 ms each way
AUTHENTICATED = "authenticated over"


def start_pubbroker_dgram(
    tmp: Path,
    model_path: Path,
    link: dict[str, Any],
    ingress_port: int,
    tag: str = "pb",
    archive: str = "archive",
    archive_opts: dict[str, Any] | None = None,
    args: tuple[str, ...] = (),
    command: list[str] | None = None,
) -> Proc:
    """A PubBroker whose link is ``link`` (transport, port or device, ...);
    ``archive_opts``: more of its archive's settings (rotate_s, ...); ``args``: more
    of its command line (--onboard-model PATH); ``command``: another build, e.g. the
    arm64 one under qemu (test_arm64_link.py)."""
    model = load_model(model_path)
    cfg = {
        "name": model["drone"]["name"],
        "link": {"host": "127.0.0.1", "key": "env:MODD_LINK_KEY", **link},
        "ingress": {"host": "127.0.0.1", "port": ingress_port},
        "archive": {"dir": str(tmp / archive), "flush_interval_ms": 200, **(archive_opts or {})},
        "topics": [{"name": t.name, "type": t.type} for t in topics(model).values()],
        "status_period_s": 60,
        "log_period_s": 1,
    }
    path = tmp / f"{tag}.json"
    path.write_text(json.dumps(cfg))
    argv = [*(command or [str(PUBBROKER)]), "--config", str(path), *args]
    proc = Proc(tag, argv, tmp / f"{tag}.log")
    assert proc.wait_log("started:", 30 if command else 10), proc.log()
    return proc


def subbroker_dgram_config(
    tmp: Path,
    model_path: Path,
    endpoint: str,
    zenoh_port: int,
    transport: str,
    device: str = "",
    tag: str = "sb",
    pb_status_s: int = 60,
    ping_period_s: float = 0.0,
) -> Path:
    """``pb_status_s``: the PubBroker's STATUS period asked in CONFIG;
    ``ping_period_s``: the SubBroker's periodic PINGs (0: none)."""
    more: dict[str, Any] = {"device": device} if device else {}
    return subbroker_config(
        tmp,
        model_path,
        endpoint,
        zenoh_port,
        tag=tag,
        transport=transport,
        pubbroker_status_period_s=pb_status_s,
        ping_period_s=ping_period_s,
        **more,
    )


def start_radio_udp(
    tmp: Path, target: int, spec: str, tag: str = "radio", relay: int | None = None
) -> tuple[Proc, int]:
    """modd-radio as a UDP relay to 127.0.0.1:target, on 127.0.0.1:``relay``
    (a new port when None), counting once a second; (process, its port)."""
    port = relay if relay is not None else free_port("udp")
    args = ["--udp", f"127.0.0.1:{port}", "--to", f"127.0.0.1:{target}", "--radio", spec]
    proc = Proc(tag, [*RADIO, *args, "--report", "1"], tmp / f"{tag}.log")
    time.sleep(0.3)
    return proc, port


def start_radio_serial(tmp: Path, spec: str, tag: str = "radio") -> tuple[Proc, str, str]:
    """modd-radio between two new pseudo-terminals; (process, base, drone)."""
    proc = Proc(tag, [*RADIO, "--serial", "--radio", spec, "--report", "1"], tmp / f"{tag}.log")
    assert proc.wait_log("drone=", 10), proc.log()
    line = next(ln for ln in proc.log().splitlines() if ln.startswith("base="))
    base, drone = (part.partition("=")[2] for part in line.split())
    return proc, base, drone


def start_backfills(zport: int, subs: Any, *span: str) -> dict[str, subprocess.Popen[str]]:
    """`modd backfill --json` for each subscriber of ``subs`` at once (one CLI each, the
    backend's credentials), over ``span`` (``--gaps``, ``--from F --to T``)."""
    env = {**os.environ, "MODD_ZENOH_CREDENTIALS": str(shared_credentials().cred_file("backend"))}
    base = [str(PYTHON), "-m", "modd_model.cli", "backfill", "--drone", "usv"]
    return {
        sub: subprocess.Popen(
            [*base, "--connect", f"tcp/127.0.0.1:{zport}", "--subscriber", sub, *span, "--json"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        for sub in subs
    }


def radio_counts(proc: Proc) -> str:
    lines = [ln for ln in proc.log().splitlines() if ln.startswith("radio:")]
    return lines[-1] if lines else ""


class Injector:
    """A UDP relay base station <-> PubBroker that, besides forwarding, sends
    the SubBroker copies of drone->base datagrams with one bit flipped
    (forged) and again as they were (replayed), and the PubBroker forged
    control datagrams."""

    def __init__(self, target: int, seed: int = 3) -> None:
        self.port = free_port("udp")
        self.front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.front.bind(("127.0.0.1", self.port))
        self.back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.back.connect(("127.0.0.1", target))
        self.rng = random.Random(seed)
        self.forged_down = self.replayed_down = self.forged_up = 0
        self.peer: tuple[str, int] | None = None
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop = True
        self._thread.join(2)
        self.front.close()
        self.back.close()

    def _run(self) -> None:
        while not self._stop:
            ready, _, _ = select.select([self.front, self.back], [], [], 0.05)
            for s in ready:
                if s is self.front:
                    data, self.peer = self.front.recvfrom(65535)
                    self.back.send(data)
                    if data[0] == 0x40:  # a forged control datagram to the PubBroker
                        bad = bytearray(data)
                        bad[-1] ^= 0x01
                        self.back.send(bytes(bad))
                        self.forged_up += 1
                    continue
                data = self.back.recv(65535)
                if self.peer is None:
                    continue
                self.front.sendto(data, self.peer)
                if data[0] in (0x30, 0x31):
                    bad = bytearray(data)
                    bad[self.rng.randrange(4, len(bad))] ^= 1 << self.rng.randrange(8)
                    self.front.sendto(bytes(bad), self.peer)
                    self.front.sendto(data, self.peer)
                    self.forged_down += 1
                    self.replayed_down += 1


def through_profile(
    tmp: Path,
    model_path: Path,
    ptys: tuple[int, str, int, str],
    profile: Any,
    load_s: float,
    signal: str = "uniform",
    status_s: int = 60,
    on_zenoh: Any = None,
) -> tuple[Any, Any]:
    """The model's processes over serial through a radio profile (the
    PubBroker's STATUS every ``status_s``): the relay in
    this process (``modd.radio.relay``, whose AirtimeChannel the caller may have
    replaced to record) between the pseudo-terminals ``ptys`` (base fd, path,
    drone fd, path), the PubBroker, the SubBroker and ``load_s`` of load; the
    relay's (up, down) channels once everything has stopped. ``on_zenoh(port)``, when
    given, is called with the SubBroker's zenoh port once it listens."""
    from modd.radio import relay
    from modd.radio.channel import RadioSpec

    base, base_path, drone, drone_path = ptys
    stopping = threading.Event()
    out: list[tuple[Any, Any]] = []
    thread = threading.Thread(
        target=lambda: out.append(
            relay.run_serial(RadioSpec(), base, drone, stopping.is_set, profile=profile)
        ),
        daemon=True,
    )
    thread.start()
    zport, ingress = free_port(), free_port()
    pb = start_pubbroker_dgram(
        tmp, model_path, {"transport": "serial", "device": drone_path, "port": 1}, ingress
    )
    sb = start_subbroker(
        tmp,
        subbroker_dgram_config(
            tmp, model_path, "127.0.0.1:1", zport, "serial", device=base_path, pb_status_s=status_s
        ),
    )
    try:
        with processes(pb, sb):
            if on_zenoh is not None:
                wait_port(zport, 40)
                on_zenoh(zport)
            assert sb.wait_log("running", 60), sb.log()[-3000:]
            load = start_load(tmp, model_path, ingress, load_s, signal=signal)
            load.p.wait(load_s + 30)
            with processes(load):
                pass
    finally:
        stopping.set()
        thread.join(10)
    return out[0]


def _stamp(line: str) -> datetime:
    return datetime.strptime(line[:23], "%Y-%m-%d %H:%M:%S,%f")


def time_to_authenticate(tmp: Path, cfg: Path, tag: str) -> float:
    """Seconds from the SubBroker's first log line (its link starts) to its link's
    authentication, by the SubBroker's own log stamps (its interpreter's start-up, slow on
    a loaded machine, left out)."""
    sb = start_subbroker(tmp, cfg, tag=tag)
    try:
        assert sb.wait_log(AUTHENTICATED, 60), sb.log()[-3000:]
        lines = sb.log().splitlines()
        done = next(ln for ln in lines if AUTHENTICATED in ln)
        return (_stamp(done) - _stamp(lines[0])).total_seconds()
    finally:
        sb.stop()


def pb_counter(pb: Proc, name: str) -> int:
    found = re.findall(rf"\b{name}=(\d+)", pb.log())
    return int(found[-1]) if found else 0
