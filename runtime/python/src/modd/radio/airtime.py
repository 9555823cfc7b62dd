"""One direction of an emulated radio with a profile (the model's
``link.radio``, docs/planning.md "Radio profiles"): each packet takes the
profile's air time (the planner's per-packet formula: Semtech's for LoRa),
and under a duty-cycle limit the radio stays silent after each transmission
for air x (1 / duty - 1), as LoRaWAN stacks enforce ETSI's limit per
sub-band. A packet offered while the radio is silent waits (``delayed``);
one that would wait more than the spec's ``queue_s`` is refused
(``dropped["duty"]``), as a modem answers "busy". The air time it measures
is what the planner's ``air_time_s_per_hour`` predicts.

>>> from modd_plan.radio import RadioProfile
>>> from modd.radio.channel import RadioSpec
>>> ch = AirtimeChannel(RadioSpec(queue_s=60), profile=RadioProfile.of({"kind": "lora"}))
>>> ch.offer(b"x" * 20, now=0.0)     # SF7/125 kHz: 56.576 ms on air
0.056576
>>> ch.offer(b"x" * 20, now=1.0)     # silent until 0.056576 x 100
5.714176
"""

from __future__ import annotations

from dataclasses import dataclass, field

from modd_plan.radio import HOUR_S, RadioProfile

from .channel import Channel


@dataclass
class AirtimeChannel(Channel):
    """A :class:`Channel` whose packets take the profile's air time (the
    spec's ``rate`` is ignored) under its duty-cycle limit."""

    profile: RadioProfile = field(default_factory=lambda: RadioProfile.of({"kind": "sik"}))
    air_s: float = 0.0  # transmitted, lost ones included (they used the air)
    radio_packets: int = 0
    delayed: int = 0
    _silent_until: float = 0.0

    def offer(self, packet: bytes, now: float) -> float | None:
        s = self.spec
        if self.in_outage(now):
            self.dropped["outage"] += 1
            return None
        begin = max(now, self._busy_until, self._silent_until)
        if begin - now > s.queue_s:
            self.dropped["duty" if begin == self._silent_until else "queue"] += 1
            return None
        if begin > max(now, self._busy_until):
            self.delayed += 1
        air, n = self.profile.packet_s(len(packet))
        end = begin + air
        self._busy_until = end
        duty = self.profile.duty_cycle
        if duty:
            self._silent_until = end + air * (1 / duty - 1)
        self.air_s += air
        self.radio_packets += n
        if self._rng.random() < s.loss:
            self.dropped["loss"] += 1
            return None
        self.passed += 1
        self.passed_bytes += len(packet)
        return round(end + s.latency_ms / 1000, 9)

    def summary(self) -> str:
        return (
            f"{super().summary()}, air {self.air_s:.6f} s in {self.radio_packets} radio "
            f"packets, delayed {self.delayed}"
        )


def energy_j(
    profile: RadioProfile, sent: AirtimeChannel, received: AirtimeChannel, elapsed_s: float
) -> float:
    """The drone radio's energy over ``elapsed_s``: transmitting ``sent``'s
    air time, receiving ``received``'s, idle the rest (the planner's model)."""
    tx, rx = sent.air_s, received.air_s
    return profile.tx_w * tx + profile.rx_w * rx + profile.idle_w * max(elapsed_s - tx - rx, 0)


def per_hour(value: float, elapsed_s: float) -> float:
    """A measurement over ``elapsed_s`` scaled to an hour."""
    return value * HOUR_S / elapsed_s if elapsed_s > 0 else 0.0
