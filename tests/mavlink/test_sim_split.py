"""Which topics `modd-sim` publishes itself: with its autopilot, only the
scientific sensors' (the mavlink sensors' topics travel over MAVLink to the
bridge); with --no-mavlink, every topic of the model."""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path

import pytest
from mavlink_harness import BIN, HERE, Proc
from modd.mavlink.decode import Decoder, Kind
from modd.ports import free_port


def _ingress_bytes(server: socket.socket, seconds: float) -> bytes:
    """Everything publishers write to a fake ingress for a while."""
    got: list[bytes] = []
    server.settimeout(0.2)
    deadline = time.monotonic() + seconds

    def read(conn: socket.socket) -> None:
        conn.settimeout(0.2)
        with conn:
            while time.monotonic() < deadline:
                try:
                    data = conn.recv(65536)
                except TimeoutError:
                    continue
                if not data:
                    return
                got.append(data)

    readers = []
    while time.monotonic() < deadline:
        try:
            conn, _ = server.accept()
        except TimeoutError:
            continue
        readers.append(threading.Thread(target=read, args=(conn,)))
        readers[-1].start()
    for r in readers:
        r.join(5)
    return b"".join(got)


@pytest.mark.parametrize("no_mavlink", [False, True])
def test_who_publishes_the_autopilot_topics(tmp_path: Path, no_mavlink: bool) -> None:
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp_port = free_port("udp")
    udp.bind(("127.0.0.1", udp_port))
    server = socket.create_server(("127.0.0.1", 0))
    argv = [
        str(BIN / "modd-sim"),
        "--model",
        str(HERE / "boat.modd"),
        "--ingress",
        f"tcp:127.0.0.1:{server.getsockname()[1]}",
        "--mavlink",
        f"udpout:127.0.0.1:{udp_port}",
    ] + (["--no-mavlink"] if no_mavlink else [])
    sim = Proc(argv, tmp_path / "sim.log")
    try:
        # the publisher waits up to 1 s for a catalogue this plain server never sends
        ingress = _ingress_bytes(server, 5.0)
        udp.settimeout(0.5)
        try:
            datagrams = [udp.recv(4096) for _ in range(3)]
        except TimeoutError:
            datagrams = []
    finally:
        code = sim.stop()
        server.close()
        udp.close()
    assert code == 0, sim.log()
    assert b"boat.ctd.water_temperature" in ingress, sim.log()
    assert (b"boat.autopilot.latitude" in ingress) is no_mavlink
    decoder = Decoder()
    kinds = {
        f.message.get_type()
        for d in datagrams
        for f in decoder.feed(d, datagram=True)
        if f.kind is Kind.MESSAGE
    }
    assert ("HEARTBEAT" in kinds) is not no_mavlink, kinds
