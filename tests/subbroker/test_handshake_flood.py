"""A stranger in radio range and a NACK storm against the datagram link, real
processes (docs/protocol.md, "Handshake under a flood" and "Resends"):

* 50 HELLO/s from a keyless stranger on the radio (modd-radio between two
  pseudo-terminals, 300 ms each way: a shared medium, every CHALLENGE heard by
  all): a restarting SubBroker still authenticates within 2 s of the time it
  takes without the stranger (was: kept out for the whole minute), and the
  PubBroker answers the flood at its CHALLENGE rate, not HELLO for HELLO.
* 1,000 of the widest NACKs from an authenticated base station: the resends
  they draw stay within the live bytes the link sent (was: 67 MB, the whole
  ring for every NACK)."""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from pathlib import Path

import pytest
from modd.link import codec
from modd.link.auth import client_proof, server_proof
from modd.link.datagram import (
    BASE_TO_DRONE,
    DGRAM_CONTROL,
    DGRAM_HANDSHAKE,
    encode_control,
    encode_handshake,
    encode_nack,
    session_key,
)
from modd.link.frames import VERSION, Auth, AuthOk, Challenge, Hello, Ping
from modd.link.serialframe import encode_frame
from modd.ports import free_port
from radio_harness import (
    RADIO_300MS,
    pb_counter,
    start_pubbroker_dgram,
    start_radio_serial,
    subbroker_dgram_config,
    time_to_authenticate,
)
from subbroker_harness import KEY, model_copy, processes, start_load, start_subbroker

pytestmark = pytest.mark.usefixtures("needs_pubbroker")


class HelloFlood:
    """A keyless stranger writing HELLOs (each with a new nonce) into the base
    station's side of the radio, ``rate`` a second, until closed."""

    def __init__(self, device: str, rate: float) -> None:
        self.fd = os.open(device, os.O_WRONLY | os.O_NOCTTY)
        self.rate, self.sent = rate, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        start = time.monotonic()
        while not self._stop.is_set():
            hello = codec.encode(Hello(VERSION, os.urandom(16)))
            os.write(self.fd, encode_frame(encode_handshake(hello)))
            self.sent += 1
            self._stop.wait(max(0.0, start + self.sent / self.rate - time.monotonic()))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        os.close(self.fd)


def test_a_stranger_flooding_hellos_on_the_radio_cannot_keep_the_base_station_out(
    tmp_path: Path,
) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    radio, base, drone = start_radio_serial(tmp_path, RADIO_300MS)
    with processes(radio):
        pb = start_pubbroker_dgram(
            tmp_path, model, {"transport": "serial", "device": drone, "port": 1}, free_port()
        )
        with processes(pb):
            cfg = subbroker_dgram_config(
                tmp_path, model, "127.0.0.1:1", free_port(), "serial", device=base
            )
            quiet = time_to_authenticate(tmp_path, cfg, "sb-quiet")
            flood = HelloFlood(base, 50)
            try:
                time.sleep(2)  # the flood is on before the SubBroker comes back
                times = [time_to_authenticate(tmp_path, cfg, f"sb-flood{i}") for i in range(3)]
            finally:
                flood.close()
            time.sleep(1.5)  # a log line with the PubBroker's counters
    print(
        f"authenticated {quiet:.2f} s after the link started without the stranger, "
        f"{', '.join(f'{t:.2f}' for t in times)} s with 50 HELLO/s ({flood.sent} HELLOs)"
    )
    challenges = pb_counter(pb, "challenges")
    print(
        f"PubBroker: {challenges} CHALLENGEs, {pb_counter(pb, 'hellos_unanswered')} HELLOs "
        f"unanswered, {pb_counter(pb, 'handshakes')} sessions"
    )
    # within 2 s (the bound: four 300 ms crossings and a CHALLENGE heard), or 1 s
    # more than without the stranger when the machine is that slow
    assert max(times) <= max(2.0, quiet + 1.0), (quiet, times)
    # the flood is answered at the CHALLENGE rate (2 a second on a shared medium, after a
    # burst of 4), not HELLO for HELLO
    seconds = flood.sent / 50
    assert challenges <= 4 + 2 * (seconds + 8) + 12, (challenges, flood.sent, pb.log()[-2000:])
    assert pb_counter(pb, "hellos_unanswered") >= flood.sent // 2


class StormClient:
    """A base station speaking the datagram link by hand over udp: the handshake,
    then whatever control frames the test sends; counts the bytes it receives."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.connect(("127.0.0.1", port))
        self.sock.settimeout(0.2)
        self.counter = 0
        self.key = self._handshake(KEY.encode())

    def _answer(self, want: type, deadline: float) -> object:
        while time.monotonic() < deadline:
            try:
                raw = self.sock.recv(65535)
            except TimeoutError:
                continue
            if raw and raw[0] == DGRAM_HANDSHAKE:
                msg = codec.decode(codec.split_frame(raw[1:]))  # type: ignore[arg-type]
                if isinstance(msg, want):
                    return msg
        raise AssertionError(f"no {want.__name__}")

    def _handshake(self, psk: bytes) -> bytes:
        nonce = os.urandom(16)
        for _ in range(5):
            self.sock.send(encode_handshake(codec.encode(Hello(VERSION, nonce))))
            try:
                ch = self._answer(Challenge, time.monotonic() + 1)
                break
            except AssertionError:
                continue
        assert isinstance(ch, Challenge)
        self.sock.send(encode_handshake(codec.encode(Auth(client_proof(psk, nonce, ch.nonce)))))
        ok = self._answer(AuthOk, time.monotonic() + 2)
        assert isinstance(ok, AuthOk) and ok.mac == server_proof(psk, nonce, ch.nonce)
        return session_key(psk, nonce, ch.nonce)

    def bytes_for(self, seconds: float, send: list[bytes] | None = None) -> int:
        """Bytes received over ``seconds``, sending ``send`` spread over the first half."""
        got, start, todo = 0, time.monotonic(), list(reversed(send or []))  # counters in order
        self.sock.settimeout(0.001)
        while (elapsed := time.monotonic() - start) < seconds:
            while todo and len(todo) > len(send or []) * (1 - 2 * elapsed / seconds):
                self.sock.send(todo.pop())
            with contextlib.suppress(TimeoutError):
                got += len(self.sock.recv(65535))
        return got

    def close(self) -> None:
        self.sock.close()

    def nack(self, ranges: list[tuple[int, int]]) -> bytes:
        self.counter += 1
        return encode_control(self.counter, encode_nack(ranges), self.key, BASE_TO_DRONE)


def test_a_nack_storm_is_resent_within_the_link_budget(tmp_path: Path) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    port, ingress = free_port("udp"), free_port()
    began = time.monotonic()
    pb = start_pubbroker_dgram(tmp_path, model, {"transport": "udp", "port": port}, ingress)
    cfg = subbroker_dgram_config(tmp_path, model, f"127.0.0.1:{port}", free_port(), "udp")
    sb = start_subbroker(tmp_path, cfg)
    load = start_load(tmp_path, model, ingress, 30)
    with processes(pb, sb, load):
        assert sb.wait_log("running", 30), sb.log()[-3000:]
        time.sleep(6)  # the resend ring fills
        sb.stop()  # the storm's base station takes the session
        client = StormClient(port)
        try:
            live = client.bytes_for(3)
            wide = [(i * 65535, 65535) for i in range(32)]
            storm = [client.nack(wide) for _ in range(1000)]
            during = client.bytes_for(3, storm)
        finally:
            client.close()
        elapsed = time.monotonic() - began
        time.sleep(1.2)  # a log line with the PubBroker's counters
    print(
        f"PubBroker: resent={pb_counter(pb, 'resent')} resend_paced="
        f"{pb_counter(pb, 'resend_paced')} nacks={pb_counter(pb, 'nacks')}"
    )
    nack_bytes = sum(len(n) for n in storm)
    resent = during - live
    print(
        f"live {live / 3:.0f} B/s; 1,000 wide NACKs ({nack_bytes} B) drew {resent} B of "
        f"resends in 3 s ({resent / nack_bytes:.2f}x the NACKs)"
    )
    assert live > 0
    # resends are earned by live DATA only: the whole storm costs at most what the link sent
    # live since the PubBroker started (twice the rate measured, for the load's variance),
    # never a ring per NACK
    assert resent <= 2 * live / 3 * elapsed, (during, live, elapsed)


def _udp(port: int) -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.connect(("127.0.0.1", port))
    s.settimeout(0.05)
    return s


def _drain(sock: socket.socket, seconds: float) -> list[bytes]:
    got, deadline = [], time.monotonic() + seconds
    while time.monotonic() < deadline:
        with contextlib.suppress(TimeoutError):
            got.append(sock.recv(65535))
    return got


def test_over_udp_a_flooding_address_gets_its_own_rate_and_the_session_its_address(
    tmp_path: Path,
) -> None:
    """udp: a stranger's address flooding HELLOs gets 2 CHALLENGEs a second (after a burst
    of 4) while a base station from another address authenticates at once; the session's
    CONTROL datagrams sent from a third address are dropped and counted (`foreign`)."""
    model = model_copy(tmp_path, "scenario1.modd")
    port = free_port("udp")
    pb = start_pubbroker_dgram(tmp_path, model, {"transport": "udp", "port": port}, free_port())
    with processes(pb):
        stranger = _udp(port)
        challenges = 0
        start = time.monotonic()
        for i in range(150):  # 3 s at 50 HELLO/s
            stranger.send(encode_handshake(codec.encode(Hello(VERSION, os.urandom(16)))))
            for raw in _drain(stranger, max(0.0, start + (i + 1) / 50 - time.monotonic())):
                challenges += raw[:1] == bytes([DGRAM_HANDSHAKE])
            if i == 75:  # mid-flood: the base station
                began = time.monotonic()
                client = StormClient(port)
                took = time.monotonic() - began
        challenges += sum(raw[:1] == bytes([DGRAM_HANDSHAKE]) for raw in _drain(stranger, 0.3))
        elsewhere = _udp(port)
        ping = codec.encode(Ping(b"where"))
        client.counter += 1
        elsewhere.send(encode_control(client.counter, ping, client.key, BASE_TO_DRONE))
        from_elsewhere = _drain(elsewhere, 0.5) + _drain(client.sock, 0.5)
        client.counter += 1
        client.sock.send(encode_control(client.counter, ping, client.key, BASE_TO_DRONE))
        from_peer = [d for d in _drain(client.sock, 1.0) if d[:1] == bytes([DGRAM_CONTROL])]
        time.sleep(1.2)  # a log line with the PubBroker's counters
        for s in (stranger, elsewhere):
            s.close()
        client.close()
    print(
        f"udp: {challenges} CHALLENGEs for 150 HELLOs in 3 s; "
        f"the base station in {took * 1000:.0f} ms"
    )
    assert challenges <= 4 + 2 * 4, challenges
    assert took < 2.0
    assert not [d for d in from_elsewhere if d[:1] == bytes([DGRAM_CONTROL])]  # no PONG
    assert pb_counter(pb, "foreign") == 1, pb.log()[-1500:]
    assert len(from_peer) >= 1  # the PONG, to the session's address
