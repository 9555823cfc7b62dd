"""The emulator's relays: UDP (a base station sends to the relay's port, the
relay forwards to the PubBroker and back) or serial (bytes between two
pseudo-terminal masters, cut into radio packets). One thread, one selector,
a heap of pending deliveries; bounded by the channel's queue."""

from __future__ import annotations

import contextlib
import heapq
import os
import selectors
import socket
import time
from collections.abc import Callable
from functools import partial

from modd_plan.radio import RadioProfile

from .airtime import AirtimeChannel
from .channel import Channel, RadioSpec

MAX_DATAGRAM = 65535
SERIAL_IDLE_S = 0.02  # bytes waiting this long go as a (short) radio packet
DUPLICATE_AFTER_S = 0.005  # a duplicated packet arrives again this much later
FORGED_AFTER_S = 0.003  # a forged copy follows the genuine packet
REPLAY_AFTER_S = 1.5  # a replayed packet comes again this much later (outside any reorder)


class _Pending:
    def __init__(self) -> None:
        self.heap: list[tuple[float, int, Callable[[], None]]] = []
        self.n = 0

    def add(self, at: float, send: Callable[[], None]) -> None:
        self.n += 1
        heapq.heappush(self.heap, (at, self.n, send))

    def run_due(self, now: float) -> float | None:
        while self.heap and self.heap[0][0] <= now:
            heapq.heappop(self.heap)[2]()
        return self.heap[0][0] - now if self.heap else None


def channels(
    spec: RadioSpec, start: float, profile: RadioProfile | None = None
) -> tuple[Channel, Channel]:
    """(up: base -> drone, down: drone -> base), seeded apart; with a radio
    profile, its air time and duty cycle (airtime.py)."""
    if profile is not None:
        return (
            AirtimeChannel(spec, spec.seed * 2 + 1, start, profile=profile),
            AirtimeChannel(spec, spec.seed * 2 + 2, start, profile=profile).hearing(),
        )
    return Channel(spec, spec.seed * 2 + 1, start), Channel(
        spec, spec.seed * 2 + 2, start
    ).hearing()


def run_udp(
    spec: RadioSpec,
    listen: tuple[str, int],
    target: tuple[str, int],
    stop: Callable[[], bool],
    report: Callable[[Channel, Channel], None] | None = None,
    report_every: float = 10.0,
    profile: RadioProfile | None = None,
) -> tuple[Channel, Channel]:
    """Relay datagrams between whoever sends to ``listen`` (the base station)
    and ``target`` (the PubBroker) until ``stop()``."""
    start = time.monotonic()
    up, down = channels(spec, start, profile)
    front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    front.bind(listen)
    back.bind((listen[0], 0))
    back.connect(target)
    peer: list[tuple[str, int]] = []
    pending = _Pending()
    sel = selectors.DefaultSelector()
    sel.register(front, selectors.EVENT_READ, "front")
    sel.register(back, selectors.EVENT_READ, "back")
    next_report = start + report_every
    try:
        while not stop():
            now = time.monotonic()
            wait = pending.run_due(now)
            for key, _ in sel.select(min(wait if wait is not None else 0.1, 0.1)):
                now = time.monotonic()
                if key.data == "front":
                    data, addr = front.recvfrom(MAX_DATAGRAM)
                    peer[:] = [addr]
                    if not data:  # the station says where it is: nothing on the air
                        continue
                    at = up.offer(data, now)
                    if at is not None:
                        _deliver(pending, up, at, back.send, data, serial=False)
                else:
                    data = back.recv(MAX_DATAGRAM)
                    at = down.offer(data, now)
                    if at is not None and peer:
                        _deliver(
                            pending, down, at, partial(_sendto, front, peer[0]), data, serial=False
                        )
            if report and time.monotonic() >= next_report:
                report(up, down)
                next_report += report_every
    finally:
        sel.close()
        front.close()
        back.close()
    return up, down


def _deliver(
    pending: _Pending,
    ch: Channel,
    at: float,
    fn: Callable[[bytes], object],
    data: bytes,
    serial: bool,
) -> None:
    """Schedule a packet that passed, with its duplicate, forgery or replay."""
    pending.add(at, partial(_send, fn, data))
    if ch.duplicates():
        pending.add(at + DUPLICATE_AFTER_S, partial(_send, fn, data))
    forged = ch.forgery(data, serial)
    if forged is not None:
        pending.add(at + FORGED_AFTER_S, partial(_send, fn, forged))
    if ch.replays():
        pending.add(at + REPLAY_AFTER_S, partial(_send, fn, data))


def _sendto(sock: socket.socket, addr: tuple[str, int], data: bytes) -> int:
    return sock.sendto(data, addr)


def _send(fn: Callable[[bytes], object], data: bytes) -> None:
    with contextlib.suppress(OSError):  # the far end is not there (yet): sent into the void
        fn(data)


def open_pty_pair() -> tuple[int, str]:
    """A pseudo-terminal in raw mode: (master fd, slave path)."""
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    os.set_blocking(master, False)
    return master, path


def run_serial(
    spec: RadioSpec,
    base_master: int,
    drone_master: int,
    stop: Callable[[], bool],
    report: Callable[[Channel, Channel], None] | None = None,
    report_every: float = 10.0,
    profile: RadioProfile | None = None,
) -> tuple[Channel, Channel]:
    """Relay bytes between two pseudo-terminal masters (the base station's and
    the drone's ends), cut into radio packets of at most ``spec.packet``
    bytes: after each 0x00 (a frame's end, as a SiK radio aligns packets to
    frames), when full, or after 20 ms without bytes."""
    start = time.monotonic()
    up, down = channels(spec, start, profile)
    limit = spec.packet or 252
    pending = _Pending()
    sel = selectors.DefaultSelector()
    bufs = {base_master: bytearray(), drone_master: bytearray()}
    last = {base_master: start, drone_master: start}
    route = {base_master: (up, drone_master), drone_master: (down, base_master)}
    for fd in bufs:
        sel.register(fd, selectors.EVENT_READ)
    next_report = start + report_every

    def flush(fd: int, packet: bytes, now: float) -> None:
        ch, out = route[fd]
        at = ch.offer(packet, now)
        if at is not None:
            _deliver(pending, ch, at, partial(os.write, out), packet, serial=True)

    try:
        while not stop():
            now = time.monotonic()
            wait = pending.run_due(now)
            for key, _ in sel.select(
                min(wait if wait is not None else SERIAL_IDLE_S, SERIAL_IDLE_S)
            ):
                fd = int(key.fd)
                try:
                    data = os.read(fd, 4096)
                except (BlockingIOError, OSError):
                    continue
                bufs[fd] += data
                last[fd] = time.monotonic()
            now = time.monotonic()
            for fd, buf in bufs.items():
                while buf:
                    cut = buf.find(0, 0, limit)
                    if cut >= 0:
                        n = cut + 1
                    elif len(buf) >= limit:
                        n = limit
                    elif now - last[fd] >= SERIAL_IDLE_S:
                        n = len(buf)
                    else:
                        break
                    flush(fd, bytes(buf[:n]), now)
                    del buf[:n]
            if report and time.monotonic() >= next_report:
                report(up, down)
                next_report += report_every
    finally:
        sel.close()
    return up, down
