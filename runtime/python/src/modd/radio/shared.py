"""A shared radio channel (docs/fleet.md, "Several stations on one radio channel"):
one radio at the drone, one modem per base station, all on one frequency. What the
drone transmits is heard by **every** station, each through its own channel (its own
loss, latency and outages, seeded apart: two stations lose different packets); what
any station transmits reaches the drone through that station's channel. The drone
sees one peer (the relay's socket: the radio it is wired to), as a PubBroker on a
serial modem does.

A station's modem is the UDP port it sends to (``listen``); the relay delivers the
drone's datagrams to the address that last sent to it (its SubBroker), as a UDP
bridge of a serial modem learns its client. A standby station (the election keeps it
silent on the air) sends an **empty** datagram now and then: the modem learns where it
is and transmits nothing (a radio sends no empty packet), and the station hears the
drone, to forward what it hears to the serving one (docs/fleet.md, "Diversity
reception").

Each station's channel may be set apart (``specs``: one per station, or one for all):
one station behind a headland (an outage), one close by (no loss).
"""

from __future__ import annotations

import selectors
import socket
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial

from .channel import Channel, RadioSpec
from .relay import MAX_DATAGRAM, _deliver, _Pending, _sendto

#: Seeds of station i's channels: the point-to-point relay's (up 2s+1, down 2s+2) for
#: station 0, then apart by this per station.
SEED_STRIDE = 1000


@dataclass
class Modem:
    """One station's modem on the shared channel: its socket, its channels, its peer."""

    sock: socket.socket
    up: Channel  # station -> drone
    down: Channel  # drone -> station
    peer: list[tuple[str, int]] = field(default_factory=list)


def modems(
    specs: Sequence[RadioSpec], listens: Sequence[tuple[str, int]], start: float
) -> list[Modem]:
    """One bound modem per station, its channels seeded apart; ``specs``: one per
    station, or one for all."""
    if len(specs) not in (1, len(listens)):
        raise ValueError(
            f"{len(specs)} radio settings for {len(listens)} stations: give one, or one each"
        )
    out = []
    for i, addr in enumerate(listens):
        spec = specs[i] if len(specs) > 1 else specs[0]
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(addr)
        seed = spec.seed * 2 + i * SEED_STRIDE
        out.append(
            Modem(sock, Channel(spec, seed + 1, start), Channel(spec, seed + 2, start).hearing())
        )
    return out


def run_shared_udp(
    specs: Sequence[RadioSpec],
    listens: Sequence[tuple[str, int]],
    target: tuple[str, int],
    stop: Callable[[], bool],
    report: Callable[[list[Modem]], None] | None = None,
    report_every: float = 10.0,
) -> list[Modem]:
    """Relay between the stations that send to ``listens`` and the PubBroker at
    ``target`` until ``stop()``: the drone's datagrams to every station (each
    station's loss drawn on its own), each station's to the drone."""
    start = time.monotonic()
    stations = modems(specs, listens, start)
    back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    back.bind((listens[0][0], 0))
    back.connect(target)
    pending = _Pending()
    sel = selectors.DefaultSelector()
    sel.register(back, selectors.EVENT_READ, None)
    for m in stations:
        sel.register(m.sock, selectors.EVENT_READ, m)
    next_report = start + report_every
    try:
        while not stop():
            wait = pending.run_due(time.monotonic())
            for key, _ in sel.select(min(wait if wait is not None else 0.1, 0.1)):
                _on_ready(key.data, back, stations, pending, time.monotonic())
            if report and time.monotonic() >= next_report:
                report(stations)
                next_report += report_every
    finally:
        sel.close()
        back.close()
        for m in stations:
            m.sock.close()
    return stations


def _on_ready(
    modem: Modem | None, back: socket.socket, stations: list[Modem], pending: _Pending, now: float
) -> None:
    if modem is not None:  # a station transmits: the drone hears it through its channel
        try:
            data, addr = modem.sock.recvfrom(MAX_DATAGRAM)
        except OSError:  # an ICMP error for a station's SubBroker that went away
            return
        modem.peer[:] = [addr]
        if not data:  # the station says where it is: nothing goes on the air
            return
        at = modem.up.offer(data, now)
        if at is not None:
            _deliver(pending, modem.up, at, back.send, data, serial=False)
        return
    try:
        data = back.recv(MAX_DATAGRAM)  # the drone transmits: every station may hear it
    except OSError:  # the PubBroker is not there (yet)
        return
    for m in stations:
        at = m.down.offer(data, now)
        if at is not None and m.peer:
            _deliver(pending, m.down, at, partial(_sendto, m.sock, m.peer[0]), data, serial=False)


def summary(stations: list[Modem]) -> str:
    """One line: what each station's channels passed and dropped."""
    return "; ".join(
        f"station {i}: base->drone {m.up.summary()}; drone->base {m.down.summary()}"
        for i, m in enumerate(stations)
    )
