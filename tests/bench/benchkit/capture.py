"""Bytes on the wire: tshark on loopback (``lo``) with a port filter for a fixed duration,
then the IP length of the packets summed per direction, IP and TCP headers included
(52 B per segment here: IPv4 20 + TCP 20 + timestamps option 12), data segments
(TCP payload > 0) and pure ACKs (no payload) apart. The server port is on the drone, so
packets from it travel drone -> base."""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from subbroker_harness import Proc


def check_capture() -> None:
    if shutil.which("tshark") is None:
        raise RuntimeError(
            "tshark is not installed: apt-get install tshark (scripts/setup.sh does)"
        )
    if os.geteuid() != 0:
        raise RuntimeError("capturing on lo needs root (or CAP_NET_RAW for dumpcap)")


@dataclass(frozen=True)
class Direction:
    bytes: int  # IP bytes, headers included
    packets: int
    data_bytes: int  # segments with a TCP payload
    data_packets: int
    ack_bytes: int  # pure ACKs (and other payload-less segments)
    ack_packets: int

    def per_s(self, seconds: float) -> dict[str, float]:
        return {
            "bytes_per_s": self.bytes / seconds,
            "packets_per_s": self.packets / seconds,
            "data_bytes_per_s": self.data_bytes / seconds,
            "data_packets_per_s": self.data_packets / seconds,
            "ack_bytes_per_s": self.ack_bytes / seconds,
            "ack_packets_per_s": self.ack_packets / seconds,
        }


@dataclass(frozen=True)
class Wire:
    seconds: float  # the capture's duration
    down: Direction  # drone -> base (from the server port)
    up: Direction  # base -> drone
    down_span: float  # seconds the counted packets of each direction cover
    up_span: float

    def rates(self) -> dict[str, dict[str, float]]:
        return {
            "drone_to_base": self.down.per_s(self.down_span),
            "base_to_drone": self.up.per_s(self.up_span),
        }


class Capture:
    """tshark on ``lo`` for ``seconds`` on ``tcp port PORT``; wait() returns the figures."""

    def __init__(self, tmp: Path, port: int, seconds: float, tag: str = "link") -> None:
        check_capture()
        self.port, self.seconds = port, seconds
        self.pcap = tmp / f"{tag}.pcap"
        self.proc = Proc(
            f"tshark-{tag}",
            [
                "tshark",
                "-q",
                "-i",
                "lo",
                "-f",
                f"tcp port {port}",
                "-a",
                f"duration:{seconds:g}",
                "-w",
                str(self.pcap),
            ],
            tmp / f"{tag}.tshark.log",
        )
        if not self.proc.wait_log("Capturing on", 15):
            self.proc.stop()
            raise RuntimeError(f"tshark did not start capturing: {self.proc.log()}")

    def wait(self) -> Wire:
        try:
            self.proc.p.wait(self.seconds + 30)
        finally:
            self.proc.stop()
        return read_pcap(self.pcap, self.port, self.seconds)


def tcp_packets(pcap: Path) -> list[tuple[float, int, int, int]]:
    """Every TCP packet of a capture (tshark): (time since the first, source
    port, IP length, TCP payload length)."""
    out = subprocess.run(
        [
            "tshark",
            "-r",
            str(pcap),
            "-T",
            "fields",
            "-e",
            "frame.time_relative",
            "-e",
            "tcp.srcport",
            "-e",
            "ip.len",
            "-e",
            "tcp.len",
        ],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return [
        (float(t), int(src), int(iplen), int(tcplen))
        for t, src, iplen, tcplen in (line.split("\t") for line in out.splitlines())
    ]


def read_pcap(pcap: Path, server_port: int, seconds: float) -> Wire:
    """Per direction, the packets from the first one up to (not including) the last one over
    the time between them: a periodic flow's exact rate, whatever the capture's edges cut.
    ``seconds`` (the capture's duration) is kept for a direction with fewer than 2 packets."""
    pkts: dict[bool, list[tuple[float, int, int]]] = {True: [], False: []}
    for t, src, iplen, tcplen in tcp_packets(pcap):
        pkts[src == server_port].append((t, iplen, tcplen))
    dirs, spans = [], []
    for down in (True, False):
        ps = pkts[down]
        span = ps[-1][0] - ps[0][0] if len(ps) >= 2 else 0.0
        body = ps[:-1] if span > 0 else ps
        data = [p[1] for p in body if p[2] > 0]
        acks = [p[1] for p in body if p[2] == 0]
        dirs.append(
            Direction(sum(data) + sum(acks), len(body), sum(data), len(data), sum(acks), len(acks))
        )
        spans.append(span if span > 0 else seconds)
    return Wire(seconds, dirs[0], dirs[1], spans[0], spans[1])
