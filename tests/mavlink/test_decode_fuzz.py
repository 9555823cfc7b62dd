"""Random bytes and garbled frames fed to the bridge's decode path: it never
raises, counts every frame it cannot use, and over UDP a good datagram after
any junk is still mapped."""

from __future__ import annotations

from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mavlink_harness import HERE, Autopilot, Recorder, load_model
from modd.mavlink.bridge import Bridge
from modd.mavlink.mapping import plan_bridge

MODEL = load_model(HERE / "boat.modd", 7171)
AP = Autopilot()
GOOD = [
    AP.heartbeat(),
    AP.attitude(0.5),
    AP.position(477_000_000, -33_500_000, 200),
    Autopilot(system=9).attitude(1.0),
]


class Wire:
    """A transport that only takes what the bridge writes."""

    def __init__(self, datagram: bool) -> None:
        self.datagram = datagram
        self.written: list[bytes] = []

    def wait(self, timeout: float) -> bool:
        return False

    def recv(self) -> bytes:
        return b""

    def write(self, data: bytes) -> None:
        self.written.append(data)

    def close(self) -> None:
        pass


def bridge(datagram: bool) -> tuple[Bridge, dict[str, Recorder]]:
    plan = plan_bridge(MODEL)
    sinks = {p.name: Recorder() for p in plan.publishers}
    return Bridge(plan, Wire(datagram), sinks, log=lambda _line: None), sinks


@st.composite
def garbled(draw: Any) -> bytes:
    """A good frame cut, flipped, spliced or doubled."""
    frame = bytearray(draw(st.sampled_from(GOOD)))
    for _ in range(draw(st.integers(0, 3))):
        i = draw(st.integers(0, len(frame) - 1))
        frame[i] = draw(st.integers(0, 255))
    cut = draw(st.integers(0, len(frame)))
    tail = draw(st.sampled_from([b"", bytes(frame[:cut]), draw(st.binary(max_size=20))]))
    return bytes(frame[:cut]) + bytes(tail)


chunks = st.lists(st.one_of(st.binary(max_size=300), garbled(), st.sampled_from(GOOD)), max_size=12)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chunks=chunks, datagram=st.booleans(), tick=st.floats(0, 100))
def test_the_decode_path_never_raises(chunks: list[bytes], datagram: bool, tick: float) -> None:
    b, _ = bridge(datagram)
    for i, data in enumerate(chunks):
        b.handle(data, now=tick + i * 0.01, now_ns=i)
        b.tick(tick + i * 0.01)
    c = b.counters
    assert min(c.mapped, c.unknown, c.bad, c.ignored, c.samples) >= 0
    b.status(tick)


@settings(max_examples=200, deadline=None)
@given(junk=st.lists(st.one_of(st.binary(min_size=1, max_size=300), garbled()), max_size=6))
def test_over_udp_a_good_datagram_after_junk_is_mapped(junk: list[bytes]) -> None:
    b, sinks = bridge(datagram=True)
    b.handle(AP.heartbeat(), now=0.0, now_ns=0)
    for data in junk:
        b.handle(data, now=0.1, now_ns=1)
    before = len(sinks["nav"].samples)
    b.handle(AP.attitude(0.25), now=0.2, now_ns=2)
    after = sinks["nav"].samples[before:]
    assert [(t, v) for t, _, v in after if t == "boat.autopilot.yaw"] == [
        ("boat.autopilot.yaw", 0.25)
    ]
