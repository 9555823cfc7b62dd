"""What the bridge maps when any local process can write to its UDP port
(docs/security.md, "MAVLink"): only the autopilot's system and component,
at most about twice the rate asked of each message, and, with a signing key,
only MAVLink 2 signed with it."""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from pathlib import Path

import pytest
from mavlink_harness import HERE, Autopilot, Recorder, load_model
from modd.mavlink.bridge import Bridge, BridgeSettings
from modd.mavlink.guard import RATE_FACTOR, signing_key
from modd.mavlink.mapping import plan_bridge
from modd.mavlink.transport import open_transport
from modd.ports import free_port

LAT = "GLOBAL_POSITION_INT"


def make_bridge(key: bytes | None = None) -> tuple[Bridge, dict[str, Recorder]]:
    plan = plan_bridge(load_model(HERE / "boat.modd", free_port()))
    sinks = {p.name: Recorder() for p in plan.publishers}
    transport = open_transport(f"udpin:127.0.0.1:{free_port('udp')}")
    return Bridge(plan, transport, sinks, BridgeSettings(signing_key=key), lambda _: None), sinks


@pytest.fixture
def bridge() -> Iterator[tuple[Bridge, dict[str, Recorder]]]:
    b, sinks = make_bridge()
    yield b, sinks
    b.transport.close()


def positions(sinks: dict[str, Recorder]) -> list[float]:
    return [v for s in sinks.values() for t, _, v in s.samples if t.endswith("latitude")]


def test_other_system_or_component_ignored(bridge: tuple[Bridge, dict[str, Recorder]]) -> None:
    b, sinks = bridge
    ours, other, spoof = Autopilot(1, 1), Autopilot(2, 1), Autopilot(1, 99)
    b.handle(ours.heartbeat(), now=0.0)
    b.handle(other.heartbeat(), now=0.01)
    b.handle(spoof.heartbeat(), now=0.02)
    b.handle(other.position(999_000_000, 0, 0), now=0.1)
    b.handle(spoof.position(888_000_000, 0, 0), now=0.2)
    assert positions(sinks) == []
    b.handle(ours.position(433_000_000, 0, 0), now=0.3)
    assert len(positions(sinks)) == 1 and abs(positions(sinks)[0] - 43.3) < 1e-6
    assert b.autopilot.system == 1 and b.autopilot.component == 1


def test_rate_is_bounded_per_message(bridge: tuple[Bridge, dict[str, Recorder]]) -> None:
    b, sinks = bridge
    ap = Autopilot(1, 1)
    b.handle(ap.heartbeat(), now=0.0)
    asked_hz = 1e6 / b.plan.intervals_us[LAT]
    for i in range(3000):  # 3,000 forged positions in one second
        b.handle(ap.position(433_000_000 + i, 0, 0), now=1.0 + i / 3000)
    got = len(positions(sinks))
    assert got <= b.rate.burst(LAT) + RATE_FACTOR * asked_hz + 1, got
    assert got < 100  # against 3,000 sent
    assert got >= asked_hz  # the autopilot's own rate passes
    assert b.counters.limited == 3000 - got


def test_signed_mavlink_only_when_a_key_is_given(tmp_path: Path) -> None:
    key_file = tmp_path / "mavlink.key"
    key_file.write_text("a passphrase shared with the autopilot\n")
    key_file.chmod(0o600)
    key = signing_key(f"file:{key_file}")
    assert key == hashlib.sha256(b"a passphrase shared with the autopilot").digest()
    b, sinks = make_bridge(key)
    try:
        unsigned = Autopilot(1, 1)
        b.handle(unsigned.heartbeat(), now=0.0)
        b.handle(unsigned.position(999_000_000, 0, 0), now=0.1)
        assert positions(sinks) == [] and b.counters.bad >= 2
        for stamp, secret in ((1, hashlib.sha256(b"wrong").digest()), (10**6, key)):
            signed = Autopilot(1, 1)
            signed.mav.signing.secret_key = secret
            signed.mav.signing.sign_outgoing = True
            signed.mav.signing.link_id = 1
            signed.mav.signing.timestamp = stamp
            b.handle(signed.heartbeat(), now=0.2)
            b.handle(signed.position(433_000_000, 0, 0), now=0.3)
        assert len(positions(sinks)) == 1 and abs(positions(sinks)[0] - 43.3) < 1e-6
    finally:
        b.transport.close()
    with pytest.raises(ValueError, match="not a regular file"):
        signing_key("file:/dev/zero")
