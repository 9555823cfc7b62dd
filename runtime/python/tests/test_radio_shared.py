"""modd-radio's shared channel (docs/fleet.md): one drone heard by two stations, each
losing its own share of the drone's datagrams. The oracle is what each station's
socket actually received."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time

from modd.ports import free_port
from modd.radio.channel import RadioSpec
from modd.radio.shared import Modem, run_shared_udp


def _drain(sock: socket.socket, timeout: float = 0.4) -> list[bytes]:
    sock.settimeout(timeout)
    got: list[bytes] = []
    try:
        while True:
            got.append(sock.recvfrom(100)[0])
    except TimeoutError:
        return got


def test_two_stations_each_hear_the_drone_with_their_own_loss() -> None:
    drone = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    drone.bind(("127.0.0.1", 0))
    ports = [free_port("udp"), free_port("udp")]
    stop = threading.Event()
    spec = RadioSpec(loss=0.2, seed=3)
    out: list[list[Modem]] = []
    listens = [("127.0.0.1", p) for p in ports]
    t = threading.Thread(
        target=lambda: out.append(run_shared_udp([spec], listens, drone.getsockname(), stop.is_set))
    )
    t.start()
    bases = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in ports]
    for b in bases:  # room for every datagram until it is read
        b.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 21)
    try:
        time.sleep(0.05)
        for base, port in zip(bases, ports, strict=True):
            base.sendto(b"hello", ("127.0.0.1", port))  # each station's modem learns its peer
        assert len(_drain(drone)) <= 2
        peer = _relay_address(bases[0], ports[0], drone)  # the one peer the drone sees
        for i in range(500):
            drone.sendto(i.to_bytes(2, "little"), peer)
            if i % 50 == 49:
                time.sleep(0.02)  # within the sockets' buffers
        heard = [{int.from_bytes(d, "little") for d in _drain(b)} for b in bases]
    finally:
        stop.set()
        t.join(5)
        for s in (*bases, drone):
            s.close()
    for got in heard:
        assert 330 < len(got) < 470, len(got)  # ~20 % lost at each station
    assert heard[0] != heard[1], "the two stations lose different datagrams"
    assert len(heard[0] | heard[1]) > 460  # ~4 % lost at both
    lost = [sum(m.down.dropped.values()) for m in out[0]]
    assert [500 - len(h) for h in heard] == lost


def _relay_address(base: socket.socket, port: int, drone: socket.socket) -> tuple[str, int]:
    """The relay's address as the drone sees it: a datagram from a station through it."""
    for _ in range(20):  # 20 % loss: a few tries
        base.sendto(b"probe", ("127.0.0.1", port))
        drone.settimeout(0.2)
        try:
            data, addr = drone.recvfrom(100)
        except TimeoutError:
            continue
        if data == b"probe":
            _drain(drone, 0.1)
            return (str(addr[0]), int(addr[1]))
    raise AssertionError("no datagram through the relay")


def test_cli_refuses_one_station_twice() -> None:
    p = subprocess.run(
        [sys.executable, "-m", "modd.radio.cli", "--udp", "127.0.0.1:9", "--udp", "127.0.0.1:9"]
        + ["--to", "127.0.0.1:10"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert p.returncode == 2 and "given twice" in p.stderr, p.stderr


def test_an_empty_datagram_teaches_the_modem_and_is_not_sent_on_the_air() -> None:
    """A standby station's empty datagram: its modem delivers the drone's datagrams to
    it from then on, and the drone receives nothing (a radio sends no empty packet).
    Each station has its own settings: a close by (no loss), b behind a headland."""
    drone = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    drone.bind(("127.0.0.1", 0))
    ports = [free_port("udp"), free_port("udp")]
    stop = threading.Event()
    specs = [RadioSpec(), RadioSpec(outages=((0.0, 600.0),))]
    listens = [("127.0.0.1", p) for p in ports]
    out: list[list[Modem]] = []
    t = threading.Thread(
        target=lambda: out.append(run_shared_udp(specs, listens, drone.getsockname(), stop.is_set))
    )
    t.start()
    bases = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in ports]
    try:
        time.sleep(0.05)
        for base, port in zip(bases, ports, strict=True):
            base.sendto(b"", ("127.0.0.1", port))
        assert _drain(drone) == [], "an empty datagram went on the air"
        bases[0].sendto(b"probe", ("127.0.0.1", ports[0]))
        drone.settimeout(1.0)
        data, peer = drone.recvfrom(100)
        assert data == b"probe"
        for i in range(50):
            drone.sendto(bytes([i]), peer)
        heard = [_drain(b) for b in bases]
    finally:
        stop.set()
        t.join(5)
        for s in (*bases, drone):
            s.close()
    assert [len(h) for h in heard] == [50, 0]
    assert out[0][1].down.dropped["outage"] == 50


def test_cli_takes_one_radio_setting_per_station_or_one_for_all() -> None:
    args = ["--udp", "127.0.0.1:1", "--udp", "127.0.0.1:2", "--to", "127.0.0.1:3"]
    run = [sys.executable, "-m", "modd.radio.cli", *args]
    three = [*run, "--radio", "loss=0.1", "--radio", "loss=0.2", "--radio", "loss=0.3"]
    bad = subprocess.run(three, capture_output=True, text=True, timeout=30)
    assert bad.returncode == 2
    assert "--radio given 3 times: give it once, or once per --udp (2 here)" in bad.stderr
