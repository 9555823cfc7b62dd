"""A keyless neighbour flooding HELLOs from many source addresses and ports against the
PubBroker's udp link, real processes (docs/protocol.md, "Keyed HELLO"; figures in
docs/reliability.md):

50 HELLO/s from 50 source ports and 2,000 HELLO/s from 250 (on 127.0.0.2-51, each with a new
nonce, each source under its own CHALLENGE limit while the flood spends the keyless budget)
straight at the PubBroker's port, while the base station (the SubBroker) restarts behind a
300 ms radio (modd-radio as a udp relay): it authenticates within 2 s of its link's start
every time (was: kept out for the whole flood), and the flood gets no more CHALLENGEs than
the keyless budget (8 a second after a burst of 8), whatever its sources."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from pathlib import Path

import pytest
from modd.link import codec
from modd.link.datagram import DGRAM_HANDSHAKE, encode_handshake
from modd.link.frames import VERSION, Hello
from modd.ports import free_port
from radio_harness import (
    RADIO_300MS,
    pb_counter,
    start_pubbroker_dgram,
    start_radio_udp,
    subbroker_dgram_config,
    time_to_authenticate,
)
from subbroker_harness import model_copy, processes

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

ADDRESSES = 50  # 127.0.0.2 .. 127.0.0.51
RESTARTS = 2


class SourcesFlood:
    """Keyless HELLOs (a new nonce each) to 127.0.0.1:``port`` from ``ports`` udp sockets
    spread over :data:`ADDRESSES` loopback addresses, ``rate`` a second in all (round robin),
    until closed; counts the CHALLENGEs they get back."""

    def __init__(self, port: int, rate: int, ports: int) -> None:
        self.socks = []
        for i in range(ports):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.bind((f"127.0.0.{2 + i % ADDRESSES}", 0))
            s.connect(("127.0.0.1", port))
            s.setblocking(False)
            self.socks.append(s)
        self.rate, self.sent, self.challenges = rate, 0, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        start = time.monotonic()
        while not self._stop.wait(0.005):
            due = int((time.monotonic() - start) * self.rate)
            while self.sent < due:
                hello = encode_handshake(codec.encode(Hello(VERSION, os.urandom(16))))
                with contextlib.suppress(BlockingIOError):
                    self.socks[self.sent % len(self.socks)].send(hello)
                self.sent += 1

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        for s in self.socks:
            with contextlib.suppress(BlockingIOError, ConnectionRefusedError):
                while True:
                    self.challenges += s.recv(2048)[:1] == bytes([DGRAM_HANDSHAKE])
            s.close()


@pytest.mark.parametrize(("rate", "ports"), [(50, 50), (2000, 250)])
def test_a_flood_from_many_sources_cannot_keep_the_base_station_out(
    tmp_path: Path, rate: int, ports: int
) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    port = free_port("udp")
    pb = start_pubbroker_dgram(tmp_path, model, {"transport": "udp", "port": port}, free_port())
    radio, relay = start_radio_udp(tmp_path, port, RADIO_300MS)
    with processes(pb, radio):
        cfg = subbroker_dgram_config(tmp_path, model, f"127.0.0.1:{relay}", free_port(), "udp")
        flood = SourcesFlood(port, rate, ports)
        began = time.monotonic()
        try:
            time.sleep(2)  # the flood is on (and the keyless budget spent) before the base station
            times = [time_to_authenticate(tmp_path, cfg, f"sb{i}") for i in range(RESTARTS)]
        finally:
            flood.close()
        seconds = time.monotonic() - began
        time.sleep(1.2)  # a log line with the PubBroker's counters
    print(
        f"{rate} HELLO/s from {ports} ports ({flood.sent} HELLOs in {seconds:.1f} s): the base "
        f"station authenticated {', '.join(f'{t:.2f}' for t in times)} s after its link "
        f"started; {flood.challenges} CHALLENGEs to the flood; PubBroker: "
        f"{pb_counter(pb, 'challenges')} CHALLENGEs, {pb_counter(pb, 'hellos_unanswered')} "
        f"unanswered, {pb_counter(pb, 'keyed_hellos')} keyed HELLOs, "
        f"{pb_counter(pb, 'handshakes')} sessions"
    )
    assert flood.sent >= rate * seconds * 0.8, (flood.sent, seconds)  # the flood was on
    assert max(times) <= 2.0, (times, pb.log()[-1500:])
    assert pb_counter(pb, "handshakes") == RESTARTS
    # the flood's CHALLENGEs: the keyless budget (8 a second after a burst of 8), whatever
    # its sources; the keyed budget is the base station's
    assert flood.challenges <= 8 + 8 * seconds + 4, (flood.challenges, seconds)
    assert pb_counter(pb, "hellos_unanswered") >= flood.sent // 2
