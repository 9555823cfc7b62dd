"""modd-radio: the channel model (rate, packet size, loss, latency, jitter,
outages; seeded), the UDP relay and the pseudo-terminal relay, and the CLI's
passed/dropped report. The oracle is what the far end actually received."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from modd.ports import free_port
from modd.radio.channel import Channel, RadioSpec
from modd.radio.relay import open_pty_pair, run_serial, run_udp


def test_spec_parse_and_errors() -> None:
    s = RadioSpec.parse("rate=3600,loss=0.05,latency_ms=80,packet=252,outage=10+30,seed=7")
    assert (s.rate, s.loss, s.latency_ms, s.packet, s.outages, s.seed) == (
        3600,
        0.05,
        80,
        252,
        ((10.0, 30.0),),
        7,
    )
    for bad, msg in (
        ("rate=x", "not a number"),
        ("loss=2", "out of range"),
        ("speed=3", "unknown radio setting 'speed'"),
        ("rate", "name=value"),
    ):
        with pytest.raises(ValueError, match=msg):
            RadioSpec.parse(bad)


def test_channel_rate_loss_outage_are_seeded() -> None:
    spec = RadioSpec(rate=1000, loss=0.2, packet=100, outages=((5, 2),), seed=3)
    a, b = Channel(spec, 9), Channel(spec, 9)
    times = [i * 0.1 for i in range(100)]
    ra = [a.offer(b"x" * 50, t) for t in times]
    assert ra == [b.offer(b"x" * 50, t) for t in times]  # same seed, same fate
    assert a.dropped["outage"] == 20  # 5.0 <= t < 7.0
    assert 5 <= a.dropped["loss"] <= 30
    assert a.offer(b"x" * 101, 20.0) is None and a.dropped["oversize"] == 1
    # back to back at 1000 B/s: 50 B takes 50 ms, the second waits for the first
    c = Channel(RadioSpec(rate=1000))
    assert c.offer(b"x" * 50, 0.0) == 0.05 and c.offer(b"x" * 50, 0.0) == 0.1
    # more than queue_s of backlog is dropped
    q = Channel(RadioSpec(rate=100, queue_s=1.0))
    fates = [q.offer(b"x" * 50, 0.0) for _ in range(5)]
    assert fates[:3] == [0.5, 1.0, 1.5] and fates[3:] == [None, None]
    assert q.dropped["queue"] == 2


def test_a_deaf_outage_silences_the_drone_to_station_direction_alone() -> None:
    """``deaf=5+2``: the station's modem hears nothing of the drone for 2 s, while
    the drone still hears the station (the relays' drone -> station channel is the
    one built with ``hearing``)."""
    spec = RadioSpec.parse("deaf=5+2,seed=3")
    assert spec.deaf == ((5.0, 2.0),) and spec.outages == ()
    talking, hearing = Channel(spec, 1), Channel(spec, 2).hearing()
    times = [i * 0.1 for i in range(100)]
    assert all(talking.offer(b"x", t) is not None for t in times)
    assert sum(hearing.offer(b"x", t) is None for t in times) == 20
    assert hearing.dropped["outage"] == 20
    with pytest.raises(ValueError, match="deaf"):
        RadioSpec.parse("deaf=5")


def test_forged_copies_pass_the_framing_and_fail_the_tag() -> None:
    """An attacker's forgery over serial has a good CRC (the deframer passes it),
    so it is the datagram's tag that refuses it; handshakes are not forged."""
    from modd.link.datagram import (
        DRONE_TO_BASE,
        DataDatagram,
        Forged,
        encode_data,
        session_key,
        verify_data,
    )
    from modd.link.serialframe import Deframer, encode_frame

    key = session_key(b"k", bytes(16), bytes(16))
    raw = encode_data(DataDatagram(1, 40, [b"\x01\x02\x03\x04"] * 3), key, DRONE_TO_BASE)
    ch = Channel(RadioSpec(forge=1.0, replay=0.5, seed=2), 4)
    for serial in (False, True):
        for _ in range(20):
            packet = encode_frame(raw) if serial else raw
            bad = ch.forgery(packet, serial)
            assert bad is not None and bad != packet
            got = Deframer(252).feed(bad) if serial else [bad]
            assert len(got) == 1 and got[0] != raw  # framing intact, datagram altered
            with pytest.raises(Forged):
                verify_data(got[0], key, DRONE_TO_BASE, 40)
    assert ch.forgery(b"\x41\x05hello", False) is None  # a handshake datagram
    assert ch.forgery(encode_frame(raw)[:-1], True) is None  # a piece of a frame
    assert 10 <= sum(ch.replays() for _ in range(40)) <= 30
    assert "forged 40" in ch.summary() and "replayed" in ch.summary()
    with pytest.raises(ValueError, match="out of range"):
        RadioSpec.parse("forge=1.5")


def test_udp_relay_both_ways_with_loss_and_latency() -> None:
    target = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target.bind(("127.0.0.1", 0))
    port = free_port("udp")
    stop = threading.Event()
    spec = RadioSpec(loss=0.2, latency_ms=30, seed=5)
    result: list[tuple[Channel, Channel]] = []
    t = threading.Thread(
        target=lambda: result.append(
            run_udp(spec, ("127.0.0.1", port), target.getsockname(), stop.is_set)
        )
    )
    t.start()
    base = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    base.settimeout(2)
    try:
        time.sleep(0.05)
        sent_at = time.monotonic()
        for i in range(200):
            base.sendto(i.to_bytes(2, "little"), ("127.0.0.1", port))
        target.settimeout(0.5)
        got: list[int] = []
        try:
            while True:
                data, relay = target.recvfrom(100)
                got.append(int.from_bytes(data, "little"))
        except TimeoutError:
            pass
        assert time.monotonic() - sent_at >= 0.03
        for i in got[:20]:  # back to the base station through the radio
            target.sendto(bytes([i]), relay)
        back = 0
        base.settimeout(0.5)
        try:
            while True:
                base.recvfrom(100)
                back += 1
        except TimeoutError:
            pass
    finally:
        stop.set()
        t.join(5)
        base.close()
        target.close()
    up, down = result[0]
    assert up.passed == len(got) and up.dropped["loss"] == 200 - len(got)
    assert 120 <= len(got) <= 185
    assert down.passed == back and back + down.dropped["loss"] == 20


def test_serial_relay_between_pseudo_terminals() -> None:
    base_master, base_path = open_pty_pair()
    drone_master, drone_path = open_pty_pair()
    stop = threading.Event()
    result: list[tuple[Channel, Channel]] = []
    spec = RadioSpec(rate=20000, packet=64, seed=1)
    t = threading.Thread(
        target=lambda: result.append(run_serial(spec, base_master, drone_master, stop.is_set))
    )
    t.start()
    import tty

    b = os.open(base_path, os.O_RDWR | os.O_NOCTTY)
    d = os.open(drone_path, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(b)
    tty.setraw(d)
    try:
        frames = b"".join(bytes([i + 1]) * 30 + b"\x00" for i in range(10))
        os.write(d, frames)
        os.set_blocking(b, False)
        got = b""
        deadline = time.monotonic() + 3
        while len(got) < len(frames) and time.monotonic() < deadline:
            try:
                got += os.read(b, 4096)
            except BlockingIOError:
                time.sleep(0.01)
        assert got == frames
    finally:
        stop.set()
        t.join(5)
        for fd in (b, d, base_master, drone_master):
            os.close(fd)
    up, down = result[0]
    assert down.passed == 10 and down.passed_bytes == len(frames)  # one packet per frame


def _wait_udp_bound(port: int, timeout: float) -> None:
    """Until some socket of this host is bound to UDP ``port`` (read from
    /proc/net/udp: probing with a bind of our own could take the port first)."""
    want = f":{port:04X}"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if any(line.split()[1].endswith(want) for line in _udp_table()):
            return
        time.sleep(0.05)
    raise AssertionError(f"nothing bound UDP port {port} within {timeout} s")


def _udp_table() -> list[str]:
    return Path("/proc/net/udp").read_text().splitlines()[1:]


def test_cli_prints_passed_and_dropped() -> None:
    target = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target.bind(("127.0.0.1", 0))
    port = free_port("udp")
    host, tport = target.getsockname()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "modd.radio.cli",
            "--udp",
            f"127.0.0.1:{port}",
            "--to",
            f"{host}:{tport}",
            "--radio",
            "loss=0.5,seed=2",
            "--duration",
            "3",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        _wait_udp_bound(port, 10.0)  # a fixed sleep lost the datagrams on a loaded machine
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for _ in range(40):
                s.sendto(b"x", ("127.0.0.1", port))
        out, _ = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
        target.close()
    assert proc.returncode == 0
    last = out.strip().splitlines()[-1]
    assert "base->drone passed" in last and "loss" in last, out
    passed = int(last.split("base->drone passed ")[1].split()[0])
    assert 8 <= passed <= 32
