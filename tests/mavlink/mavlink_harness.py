"""What the MAVLink tests share: free loopback ports, the test model, processes
stopped by PID, the real PubBroker from configs generated from the model, the
MCAP archive read with the official reader, and MAVLink frames built by hand."""

from __future__ import annotations

import json
import os
import signal
import struct
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
BIN = Path(sys.executable).parent
PUBBROKER = REPO / "build" / "bin" / "modd-pubbroker"
LINK_KEY = "mavlink-test-key"


class Proc:
    """A process with its output in a log file; stop() sends SIGTERM, then kills."""

    def __init__(self, argv: list[str], log: Path, env: dict[str, str] | None = None) -> None:
        self.log_path = log
        self._out = log.open("wb")
        self.popen = subprocess.Popen(
            argv, stdout=self._out, stderr=subprocess.STDOUT, env=env or dict(os.environ)
        )

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait_for(self, text: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.log():
                return
            if self.popen.poll() is not None:
                break
            time.sleep(0.05)
        raise AssertionError(f"{text!r} never appeared in {self.log_path}:\n{self.log()}")

    def stop(self, timeout: float = 10.0) -> int:
        p = self.popen
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(5)
        self._out.close()
        return int(p.returncode)


def load_model(path: Path, link_port: int) -> dict[str, Any]:
    """The model at ``path`` with its PubBroker's link on ``link_port``."""
    from modd_model import load_text

    text = path.read_text().replace('"127.0.0.1":7171', f'"127.0.0.1":{link_port}')
    result = load_text(text, str(path), "modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    model: dict[str, Any] = result.model
    return model


def start_pubbroker(model: dict[str, Any], workdir: Path) -> tuple[Proc, dict[str, Any], Path]:
    """The real PubBroker from the operator configs generated for ``model`` (archive and
    ingress socket under workdir); returns it, the local model and the model.json path."""
    from modd_launch.drone import prepare

    if not PUBBROKER.is_file():
        pytest.fail(f"{PUBBROKER} is missing: run `make build`")
    local, configs = prepare(model, workdir)
    env = dict(os.environ, MODD_LINK_KEY=LINK_KEY)
    proc = Proc(
        [str(PUBBROKER), "--config", str(configs / "pubbroker.json")],
        workdir / "pubbroker.log",
        env,
    )
    sock = Path(local["pubBroker"]["ingress"]["unixSocket"])
    deadline = time.monotonic() + 10
    while not sock.exists():
        if time.monotonic() > deadline or proc.popen.poll() is not None:
            proc.stop()
            raise AssertionError(f"the PubBroker did not start:\n{proc.log()}")
        time.sleep(0.05)
    return proc, local, configs / "model.json"


def f32(x: float) -> float:
    return float(struct.unpack("<f", struct.pack("<f", x))[0])


def read_archive(directory: Path) -> dict[str, list[tuple[int, Any]]]:
    """(log time ns, value) of every archived sample, by topic, in time order."""
    from mcap.reader import make_reader

    out: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    for path in sorted(directory.glob("*.mcap")):
        with path.open("rb") as f:
            for _schema, channel, message in make_reader(f).iter_messages():
                value = json.loads(message.data)["value"]
                if channel.metadata.get("type") == "float32":
                    value = f32(value)
                out[channel.topic].append((message.log_time, value))
    for samples in out.values():
        samples.sort(key=lambda s: s[0])
    return dict(out)


class Recorder:
    """A publisher stand-in: records what the bridge publishes."""

    def __init__(self) -> None:
        self.declared: dict[str, str] = {}
        self.samples: list[tuple[str, int, Any]] = []
        self.flushed = self.closed = False

    def declare(self, topic: str, vtype: str) -> None:
        self.declared[topic] = vtype

    def publish(self, topic: str, timestamp_ns: int, value: Any) -> bool:
        self.samples.append((topic, timestamp_ns, value))
        return True

    def flush(self, timeout: float = 5.0) -> bool:
        self.flushed = True
        return True

    def close(self, timeout: float = 2.0) -> None:
        self.closed = True


class Autopilot:
    """Hand-built MAVLink 2 frames from an autopilot (system 1, component 1 by default)."""

    def __init__(self, system: int = 1, component: int = 1) -> None:
        from modd.mavlink.dialect import parser

        self.mav = parser(system, component)

    def frame(self, msg: Any) -> bytes:
        data = bytes(msg.pack(self.mav))
        self.mav.seq = (self.mav.seq + 1) % 256
        return data

    def heartbeat(self) -> bytes:
        from modd.mavlink.dialect import MAV

        return self.frame(
            MAV.MAVLink_heartbeat_message(
                MAV.MAV_TYPE_SURFACE_BOAT,
                MAV.MAV_AUTOPILOT_ARDUPILOTMEGA,
                0,
                0,
                MAV.MAV_STATE_ACTIVE,
                3,
            )
        )

    def attitude(self, yaw: float, boot_ms: int = 1000) -> bytes:
        from modd.mavlink.dialect import MAV

        return self.frame(MAV.MAVLink_attitude_message(boot_ms, 0.0, 0.0, yaw, 0.0, 0.0, 0.0))

    def position(self, lat_e7: int, lon_e7: int, alt_mm: int, boot_ms: int = 1000) -> bytes:
        from modd.mavlink.dialect import MAV

        return self.frame(
            MAV.MAVLink_global_position_int_message(
                boot_ms, lat_e7, lon_e7, alt_mm, alt_mm, 0, 0, 0, 0
            )
        )

    def ack(self, command: int, result: int) -> bytes:
        from modd.mavlink.dialect import MAV

        return self.frame(MAV.MAVLink_command_ack_message(command, result, 0, 0, 255, 191))


def unknown_frame(msgid: int = 0x00F0F0, payload: bytes = b"\x01\x02\x03") -> bytes:
    """A well-formed MAVLink 2 frame of a message id no dialect defines (its CRC cannot
    be checked without the id's CRC_EXTRA: any two bytes do)."""
    header = bytes([0xFD, len(payload), 0, 0, 7, 1, 1]) + msgid.to_bytes(3, "little")
    return header + payload + b"\x00\x00"


def corrupt_crc(frame: bytes) -> bytes:
    return frame[:-1] + bytes([frame[-1] ^ 0xFF])
