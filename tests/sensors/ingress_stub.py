"""A stand-in for the PubBroker's ingress (the real protocol: HELLO, CATALOGUE,
REGISTER, SAMPLES, ACK, HEALTH) that keeps every sample as published, timestamp
and all, with no bound on timestamps: the instrument-clock tests stamp samples
in other years than the computer's, which the real ingress refuses by design.
"""

from __future__ import annotations

import socket
import threading
from pathlib import Path

from modd.ingress import (
    HEALTH,
    HELLO,
    REGISTER,
    SAMPLES,
    Ack,
    Catalogue,
    encode_ack,
    encode_catalogue,
)
from modd.link.codec import FrameSplitter, Reader
from modd.link.frames import ValueType

_FORMAT = {
    ValueType.FLOAT32: "<f",
    ValueType.FLOAT64: "<d",
    ValueType.INT: "<q",
    ValueType.BOOL: "<B",
}


class RecordingIngress:
    """Listens on a unix socket; ``samples[topic]`` is [(timestamp_ns, value), ...]."""

    def __init__(self, path: Path, drone: str) -> None:
        self.drone = drone
        self.server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.server.bind(str(path))
        self.server.listen(16)
        self.samples: dict[str, list[tuple[int, float]]] = {}
        self.lock = threading.Lock()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.server.accept()
            except OSError:
                return
            threading.Thread(target=self._serve_and_close, args=(conn,), daemon=True).start()

    def _serve_and_close(self, conn: socket.socket) -> None:
        with conn:
            self._serve(conn)

    def _serve(self, conn: socket.socket) -> None:
        splitter, received = FrameSplitter(), 0
        # frames are read whole: a frame the stub cannot read is a test failure
        names: dict[int, str] = {}
        types: dict[int, ValueType] = {}
        conn.sendall(encode_catalogue(Catalogue(self.drone, accept_unknown=True)))
        while data := _recv(conn):
            for f in splitter.feed(data):
                r = Reader(f.body)
                if f.type == REGISTER:
                    lid, vtype = r.varint(), ValueType(r.u8())
                    names[lid], types[lid] = r.string(255), vtype
                elif f.type == SAMPLES:
                    n = r.varint()
                    got = []
                    for _ in range(n):
                        lid = r.varint()
                        stamp = int(r.fixed("<q"))
                        got.append((names[lid], stamp, float(r.fixed(_FORMAT[types[lid]]))))
                    self.received(got)
                    received += n
                    conn.sendall(encode_ack(Ack(received, received, received)))
                elif f.type not in (HELLO, HEALTH):
                    raise RuntimeError(f"unexpected ingress frame {f.type}")

    def received(self, samples: list[tuple[str, int, float]]) -> None:
        """Called with each SAMPLES frame's (topic, timestamp_ns, value): kept by topic."""
        with self.lock:
            for topic, stamp, value in samples:
                self.samples.setdefault(topic, []).append((stamp, value))

    def topic(self, name: str) -> list[tuple[int, float]]:
        with self.lock:
            return list(self.samples.get(name, []))

    def close(self) -> None:
        self.server.close()


def _recv(conn: socket.socket) -> bytes:
    try:
        return conn.recv(65536)
    except OSError:
        return b""
