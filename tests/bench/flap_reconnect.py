"""Reconnect cost of a flapping link: the SubBroker's LinkClient to the real PubBroker through
a loopback TCP proxy that cuts the connection every PERIOD seconds; prints the time from each
cut until the link is up again (authenticated, RTT measured). docs/reliability.md.

Run: .venv/bin/python tests/bench/flap_reconnect.py [CUTS] [PERIOD_S]
"""

from __future__ import annotations

import socket
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "runtime"))

import contextlib

from modd.link.frames import AuthOk, Config, ConfigAck, Status  # noqa: E402
from modd.link.receiver import Window  # noqa: E402
from modd.ports import free_port  # noqa: E402
from modd.subbroker.config import LinkOptions  # noqa: E402
from modd.subbroker.link import LinkClient  # noqa: E402
from pubbroker_harness import KEY, PubBroker  # noqa: E402


class Quiet:
    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | None:
        return None

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None: ...
    def on_windows(self, windows: list[Window]) -> None: ...
    def on_status(self, status: Status) -> None: ...
    def on_down(self, reason: str) -> None: ...


class Proxy(threading.Thread):
    """Forwards 127.0.0.1:port to the broker; cut() closes the current pair."""

    def __init__(self, target: int) -> None:
        super().__init__(daemon=True)
        self.port = free_port()
        self.target = target
        self.pair: list[socket.socket] = []
        self.srv = socket.create_server(("127.0.0.1", self.port))

    def run(self) -> None:
        while True:
            c, _ = self.srv.accept()
            u = socket.create_connection(("127.0.0.1", self.target))
            self.pair = [c, u]
            for a, b in ((c, u), (u, c)):
                threading.Thread(target=self.pump, args=(a, b), daemon=True).start()

    @staticmethod
    def pump(a: socket.socket, b: socket.socket) -> None:
        try:
            while data := a.recv(65536):
                b.sendall(data)
        except OSError:
            pass
        for s in (a, b):
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)

    def cut(self) -> None:
        for s in self.pair:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)


def main() -> None:
    cuts = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    period = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    with tempfile.TemporaryDirectory() as tmp, PubBroker(Path(tmp)) as b:
        proxy = Proxy(b.link_port)
        proxy.start()
        link = LinkClient(("127.0.0.1", proxy.port), KEY, LinkOptions(), Quiet())
        link.start()
        while link.stats.state != "up":
            time.sleep(0.001)
        costs = []
        for _ in range(cuts):
            time.sleep(period)
            proxy.cut()
            t = time.monotonic()
            while link.stats.state == "up" and time.monotonic() - t < 5:
                time.sleep(0.0005)
            while link.stats.state != "up" and time.monotonic() - t < 10:
                time.sleep(0.0005)
            costs.append(time.monotonic() - t)
        link.stop()
    print(
        f"{cuts} cuts every {period} s: reconnect (cut -> authenticated, RTT measured) "
        f"median {statistics.median(costs) * 1000:.1f} ms, max {max(costs) * 1000:.1f} ms"
    )


if __name__ == "__main__":
    main()
