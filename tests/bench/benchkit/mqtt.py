"""MQTT for the peer benchmarks: Debian's Mosquitto started on free loopback ports with its
own config file in a temporary directory, and the few MQTT 3.1.1 packets the drone-side
publishers and the ingest blaster write by hand (QoS 0 PUBLISH, CONNECT; a QoS 1 PUBLISH
as an end marker whose PUBACK proves the broker read everything before it).

The broker gets two listeners: one for the drone's own publishers (never on the link) and
one for the base-station subscribers (the link, captured by tshark).
"""

from __future__ import annotations

import shutil
import socket
import struct
from pathlib import Path

from subbroker_harness import Proc, free_port, wait_port

PAYLOAD = struct.Struct("<qfI")  # 16 bytes: publish time ns, float32 value, sequence
MOSQUITTO = "mosquitto"


def remaining_length(n: int) -> bytes:
    out = bytearray()
    while True:
        b, n = n % 128, n // 128
        out.append(b | (0x80 if n else 0))
        if not n:
            return bytes(out)


def utf8(s: str) -> bytes:
    data = s.encode()
    return struct.pack(">H", len(data)) + data


def connect_packet(client_id: str, keepalive_s: int = 60) -> bytes:
    body = utf8("MQTT") + bytes([4, 0x02]) + struct.pack(">H", keepalive_s) + utf8(client_id)
    return b"\x10" + remaining_length(len(body)) + body


def publish_packet(topic: str, payload: bytes) -> bytes:
    """QoS 0, no retain: 2 B fixed header (short packets), 2 B topic length, topic, payload."""
    body = utf8(topic) + payload
    return b"\x30" + remaining_length(len(body)) + body


def publish_qos1_packet(topic: str, payload: bytes, packet_id: int = 1) -> bytes:
    body = utf8(topic) + struct.pack(">H", packet_id) + payload
    return b"\x32" + remaining_length(len(body)) + body


def mqtt_topic(topic: str) -> str:
    """usv.accelerometer.accel_x -> usv/accelerometer/accel_x (same length)."""
    return topic.replace(".", "/")


def open_client(port: int, client_id: str) -> socket.socket:
    """A raw MQTT connection, CONNACK read."""
    s = socket.create_connection(("127.0.0.1", port), timeout=10)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    s.sendall(connect_packet(client_id))
    ack = recv_exact(s, 4)
    if ack[0] != 0x20 or ack[3] != 0:
        raise RuntimeError(f"Mosquitto refused the connection: CONNACK {ack.hex()}")
    return s


def recv_exact(s: socket.socket, n: int) -> bytes:
    buf = b""
    while len(buf) < n:
        chunk = s.recv(n - len(buf))
        if not chunk:
            raise ConnectionError("Mosquitto closed the connection")
        buf += chunk
    return buf


def wait_puback(s: socket.socket, packet_id: int = 1, timeout_s: float = 120.0) -> None:
    s.settimeout(timeout_s)
    while True:
        head = recv_exact(s, 2)
        body = recv_exact(s, head[1])
        if head[0] == 0x40 and struct.unpack(">H", body)[0] == packet_id:
            return


def check_installed() -> str:
    path = shutil.which(MOSQUITTO) or shutil.which("/usr/sbin/mosquitto")
    if path is None:
        raise RuntimeError(
            "mosquitto is not installed: apt-get install mosquitto (scripts/setup.sh does)"
        )
    return path


class Mosquitto:
    """The broker on two free loopback ports: ``drone_port`` for drone-side publishers,
    ``link_port`` for base-station subscribers. Stopped by PID."""

    def __init__(self, tmp: Path, cpu: int | None = None, sys_interval_s: int = 0) -> None:
        binary = check_installed()
        self.drone_port, self.link_port = free_port(), free_port()
        conf = tmp / "mosquitto.conf"
        conf.write_text(
            "\n".join(
                [
                    "user root",  # we run as root in CI; do not switch to the mosquitto user
                    "persistence false",
                    "log_dest stderr",
                    "log_type error",
                    "log_type warning",
                    f"sys_interval {sys_interval_s}",
                    "max_queued_messages 100000",
                    "allow_anonymous true",
                    f"listener {self.drone_port} 127.0.0.1",
                    f"listener {self.link_port} 127.0.0.1",
                    "",
                ]
            )
        )
        cmd = [binary, "-c", str(conf)]
        if cpu is not None:
            cmd = ["taskset", "-c", str(cpu), *cmd]
        self.proc = Proc("mosquitto", cmd, tmp / "mosquitto.log")
        wait_port(self.drone_port)
        wait_port(self.link_port)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def stop(self) -> None:
        self.proc.stop()
