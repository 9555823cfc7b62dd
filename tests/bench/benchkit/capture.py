"""Bytes on the wire: tshark on loopback (``lo``) with a port filter for a fixed duration,
then the IP length of every packet summed per direction, IP and TCP headers included
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
        raise RuntimeError("tshark is not installed: apt-get install tshark "
                           "(scripts/setup.sh does)")
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
        return {"bytes_per_s": self.bytes / seconds, "packets_per_s": self.packets / seconds,
                "data_bytes_per_s": self.data_bytes / seconds,
                "data_packets_per_s": self.data_packets / seconds,
                "ack_bytes_per_s": self.ack_bytes / seconds,
                "ack_packets_per_s": self.ack_packets / seconds}


@dataclass(frozen=True)
class Wire:
    seconds: float
    down: Direction  # drone -> base (from the server port)
    up: Direction  # base -> drone

    def rates(self) -> dict[str, dict[str, float]]:
        return {"drone_to_base": self.down.per_s(self.seconds),
                "base_to_drone": self.up.per_s(self.seconds)}


class Capture:
    """tshark on ``lo`` for ``seconds`` on ``tcp port PORT``; wait() returns the figures."""

    def __init__(self, tmp: Path, port: int, seconds: float, tag: str = "link") -> None:
        check_capture()
        self.port, self.seconds = port, seconds
        self.pcap = tmp / f"{tag}.pcap"
        self.proc = Proc(f"tshark-{tag}", [
            "tshark", "-q", "-i", "lo", "-f", f"tcp port {port}",
            "-a", f"duration:{seconds:g}", "-w", str(self.pcap)], tmp / f"{tag}.tshark.log")
        if not self.proc.wait_log("Capturing on", 15):
            self.proc.stop()
            raise RuntimeError(f"tshark did not start capturing: {self.proc.log()}")

    def wait(self) -> Wire:
        try:
            self.proc.p.wait(self.seconds + 30)
        finally:
            self.proc.stop()
        return read_pcap(self.pcap, self.port, self.seconds)


def read_pcap(pcap: Path, server_port: int, seconds: float) -> Wire:
    out = subprocess.run(
        ["tshark", "-r", str(pcap), "-T", "fields", "-e", "tcp.srcport", "-e", "ip.len",
         "-e", "tcp.len"], check=True, capture_output=True, text=True).stdout
    acc = {True: [0] * 6, False: [0] * 6}
    for line in out.splitlines():
        src, iplen, tcplen = line.split("\t")
        a = acc[int(src) == server_port]
        n = int(iplen)
        a[0] += n
        a[1] += 1
        k = 2 if int(tcplen) > 0 else 4
        a[k] += n
        a[k + 1] += 1
    return Wire(seconds, Direction(*acc[True]), Direction(*acc[False]))
