"""The radio's share of a plan: air time and packets per hour, the duty-cycle
limit, energy per hour and the declared battery (docs/planning.md, "Radio
profiles").

A model's ``link.radio`` names the radio (sik, wifi, lora) and may override
any default below. Each packet of the link budget's walk
(:attr:`LinkBudget.packet_sizes`, bytes on the wire) is one radio packet, or
several when it exceeds the radio's largest payload (a transparent modem
splits the serial stream); the base station's packets (keepalives, TCP ACKs)
are received. Energy per hour = tx W x air time + rx W x receive time +
idle W x the rest of the hour.

Default powers, from the datasheets (check your module's; override them):

* lora: Semtech SX1276 datasheet, table "Supply current", 3.3 V: transmit
  +17 dBm on PA_BOOST 87 mA (0.287 W), receive 125 kHz 10.8 mA (0.0356 W),
  standby 1.6 mA (0.00528 W).
* sik: RFDesign RFD900 datasheet, 5 V: transmit +30 dBm about 800 mA (4 W),
  receive about 30 mA (0.15 W); a SiK radio listens between packets, so idle
  is receive.
* wifi: Espressif ESP32 datasheet, 3.3 V: transmit 802.11g about 190 mA
  (0.627 W), receive about 100 mA (0.33 W); an associated station listens,
  so idle is receive.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from math import ceil
from typing import Any, Literal

from modd_contracts.types_gen import PlanRadio

from .airtime import lora_time_on_air, sik_time_on_air, wifi_time_on_air
from .calibration import CalibrationUse
from .linkbudget import KEEPALIVE_BYTES, KEEPALIVE_S, LinkBudget, wire_bytes
from .linkcost import TCP_IP_HEADER_BYTES

HOUR_S = 3600.0
#: largest LoRa payload per spreading factor: LoRaWAN Regional Parameters
#: (RP002), EU863-870 data rates DR0-DR5, M (MAC payload) column
LORA_MAX_PAYLOAD = {6: 250, 7: 250, 8: 250, 9: 123, 10: 59, 11: 59, 12: 59}
#: kind -> (tx W, rx W, idle W, air rate bit/s, largest payload B, duty cycle)
DEFAULTS: dict[str, tuple[float, float, float, int, int, float | None]] = {
    "lora": (0.287, 0.0356, 0.00528, 0, 0, 0.01),
    "sik": (4.0, 0.15, 0.15, 64_000, 252, None),
    "wifi": (0.627, 0.33, 0.33, 24_000_000, 1500, None),
}


@dataclass(frozen=True)
class RadioProfile:
    """A model's ``link.radio`` with every default filled in."""

    kind: str
    tx_w: float
    rx_w: float
    idle_w: float
    max_payload: int
    duty_cycle: float | None = None
    battery_wh: float | None = None
    air_rate_bps: int = 0
    ecc: bool = False
    sf: int = 7
    bandwidth_hz: int = 125_000
    coding_rate: int = 5
    preamble: int = 8
    explicit_header: bool = True
    crc: bool = True
    low_data_rate: bool | None = None

    @staticmethod
    def of(radio: Mapping[str, Any]) -> RadioProfile:
        """From a validated ``link.radio`` object (decimals are strings)."""
        kind = radio["kind"]
        tx, rx, idle, rate, payload, duty = DEFAULTS[kind]
        sf = int(radio.get("spreadingFactor", 7))
        if kind == "lora":
            payload = LORA_MAX_PAYLOAD[sf]

        def dec(key: str, default: float | None) -> float | None:
            return float(radio[key]) if key in radio else default

        return RadioProfile(
            kind=kind,
            tx_w=dec("txW", tx) or 0.0,
            rx_w=dec("rxW", rx) or 0.0,
            idle_w=dec("idleW", idle) or 0.0,
            max_payload=int(radio.get("maxPayload", payload)),
            duty_cycle=dec("dutyCycle", duty),
            battery_wh=dec("batteryWh", None),
            air_rate_bps=int(radio.get("airRateBps", rate)),
            ecc=bool(radio.get("ecc", False)),
            sf=sf,
            bandwidth_hz=int(radio.get("bandwidthHz", 125_000)),
            coding_rate=int(radio.get("codingRate", 5)),
            preamble=int(radio.get("preamble", 8)),
            explicit_header=bool(radio.get("explicitHeader", True)),
            crc=bool(radio.get("crc", True)),
            low_data_rate=radio.get("lowDataRate"),
        )

    def one_packet_s(self, payload: int) -> float:
        """Air time of one radio packet of ``payload`` bytes."""
        if self.kind == "lora":
            return lora_time_on_air(
                payload,
                self.sf,
                self.bandwidth_hz,
                self.coding_rate,
                self.preamble,
                self.explicit_header,
                self.crc,
                self.low_data_rate,
            )
        if self.kind == "sik":
            return sik_time_on_air(payload, self.air_rate_bps, self.ecc)
        return wifi_time_on_air(payload, self.air_rate_bps)

    def packet_s(self, size: int) -> tuple[float, int]:
        """Air time and radio packets of ``size`` bytes handed to the radio
        (split into packets of at most :attr:`max_payload`)."""
        n = max(1, ceil(size / self.max_payload))
        full, last = divmod(size, self.max_payload)
        air = full * self.one_packet_s(self.max_payload)
        if last:
            air += self.one_packet_s(last)
        return air, n


@dataclass(frozen=True)
class SubscriptionCost:
    """A subscription's share of the air time: the air time of the streams it
    is served by, split in proportion to their value bytes/s (headers
    included), a stream shared by several subscriptions split evenly."""

    name: str
    bytes_per_s: float
    air_s_per_hour: float


@dataclass(frozen=True)
class RadioReport:
    """Per hour of the plan, on the declared radio."""

    profile: RadioProfile
    bytes_per_s: float
    packets_per_hour: float
    air_s_per_hour: float
    rx_s_per_hour: float
    energy_j_per_hour: float
    costs: tuple[SubscriptionCost, ...]
    #: quantised values (resolution.py): True, every one sized at its declared
    #: range, the figures are upper bounds (a smaller signal costs less); False,
    #: some are deltas assumed small, the figures are estimates; None, exact
    upper_bound: bool | None = None
    #: the plan's bound when its figures are an estimate (deltas sized at the
    #: declared range's width, resolution.py): the duty-cycle limit's check
    ceiling: RadioReport | None = None
    #: the archive the quantised values were sized from (calibration.py):
    #: its per-stream mean sizes, and the streams it had no sample of
    calibration: CalibrationUse | None = None
    #: of air_s_per_hour, the link's control traffic's (control.py): an
    #: estimate (its STATUS sizes vary), so the figures are one
    control_s_per_hour: float = 0.0
    with_control: bool = False

    @property
    def hedge(self) -> bool | None:
        """True: the figures bound the radio's; False: an estimate; None: exact."""
        return False if self.with_control else self.upper_bound

    @property
    def at_most(self) -> str:
        """What the figures are, before them: "at most ", "about " or ""."""
        return {True: "at most ", False: "about ", None: ""}[self.hedge]

    @property
    def duty_share(self) -> float | None:
        """Air time over the duty-cycle limit's (1.0: exactly at the limit),
        the bound's when the figures are an estimate with one."""
        limit = self.profile.duty_cycle
        air = self.ceiling.air_s_per_hour if self.ceiling else self.air_s_per_hour
        return air / (limit * HOUR_S) if limit else None

    @property
    def battery_share(self) -> float | None:
        """Share of the declared battery the radio uses per hour."""
        wh = self.profile.battery_wh
        return self.energy_j_per_hour / (wh * HOUR_S) if wh else None

    @property
    def fits(self) -> bool:
        share = self.duty_share
        return share is None or share <= 1.0

    @property
    def error(self) -> str | None:
        """Why the plan is refused (over the duty-cycle limit), naming the
        subscriptions that cost most, else None."""
        if self.fits:
            return None
        p = self.profile
        top = ", ".join(
            f"{c.name} {c.air_s_per_hour:.1f} s/h ({c.bytes_per_s:.1f} B/s)" for c in self.costs[:5]
        )
        most = f" (at most {self.ceiling.air_s_per_hour:.1f} s)" if self.ceiling else ""
        return (
            f"the plan transmits {self.at_most}{self.air_s_per_hour:.1f} s{most} per hour on "
            f"the {p.kind} "
            f"radio, over its duty-cycle limit of {100 * (p.duty_cycle or 0):g} % "
            f"({(p.duty_cycle or 0) * HOUR_S:.1f} s per hour); the subscriptions that cost "
            f"most: {top}"
        )

    @property
    def figures(self) -> Literal["exact", "upper_bound", "estimate"]:
        """What the figures are, for the plan JSON (:attr:`upper_bound`)."""
        kinds: dict[bool | None, Literal["exact", "upper_bound", "estimate"]] = {
            True: "upper_bound",
            False: "estimate",
            None: "exact",
        }
        return kinds[self.hedge]

    @property
    def air_bound_s_per_hour(self) -> float | None:
        """The bound's air time when the figures are an estimate with one."""
        return round(self.ceiling.air_s_per_hour, 3) if self.ceiling else None

    def to_json(self) -> PlanRadio:
        """The report (``diagnostics`` and ``proposals`` empty: planjson.py
        locates the refusal in the model and adds the proposals); a
        calibrated one adds ``calibrated_from`` and ``calibration``."""
        share, battery = self.duty_share, self.battery_share
        out: PlanRadio = {
            "kind": self.profile.kind,  # type: ignore[typeddict-item]  # checked by RadioProfile.of
            "bytes_per_s": round(self.bytes_per_s, 3),
            "packets_per_hour": round(self.packets_per_hour, 3),
            "air_time_s_per_hour": round(self.air_s_per_hour, 3),
            "duty_cycle": self.profile.duty_cycle,
            "duty_share": round(share, 6) if share is not None else None,
            "figures": self.figures,
            "air_time_bound_s_per_hour": self.air_bound_s_per_hour,
            "energy_j_per_hour": round(self.energy_j_per_hour, 3),
            "battery_wh": self.profile.battery_wh,
            "battery_share_per_hour": round(battery, 6) if battery is not None else None,
            "costs": [
                {
                    "subscription": c.name,
                    "bytes_per_s": round(c.bytes_per_s, 3),
                    "air_time_s_per_hour": round(c.air_s_per_hour, 3),
                }
                for c in self.costs
            ],
            "error": self.error,
            "diagnostics": [],
            "proposals": [],
        }
        if self.calibration is not None:  # absent otherwise: uncalibrated JSON unchanged
            out["calibrated_from"] = self.calibration.source
            out["calibration"] = self.calibration.to_json()
        return out


def radio_report(
    profile: RadioProfile,
    budget: LinkBudget,
    upper_bound: bool | None = None,
    ceiling: LinkBudget | None = None,
    calibration: CalibrationUse | None = None,
) -> RadioReport:
    """The radio's figures for a plan's link budget (its walked packets
    scaled to an hour, and its control traffic's); ``upper_bound`` as
    :attr:`RadioReport.upper_bound`; ``ceiling``, the budget of the bound
    when ``budget`` is an estimate; ``calibration``, what the sizes were
    measured on. With control traffic (an estimate: its counters vary) the
    figures are an estimate and the report carries its bound: the DATA's
    bound (``ceiling``, else the DATA figures) with the control's bound."""
    data_h, packets_h = _data_air(profile, budget)
    control_h, control_packets_h = _control_air(profile, budget.control_about)
    air_h = data_h + control_h
    transport = budget.settings.transport
    if transport == "tcp":  # one pure ACK back per segment
        acks = len(budget.packet_sizes) * _scale(budget) + control_packets_h
        rx_h = profile.packet_s(TCP_IP_HEADER_BYTES)[0] * acks
    else:
        rx_h = profile.packet_s(wire_bytes(transport, KEEPALIVE_BYTES))[0] * HOUR_S / KEEPALIVE_S
    rx_h = min(rx_h, HOUR_S - min(air_h, HOUR_S))
    idle_h = max(HOUR_S - air_h - rx_h, 0.0)
    energy = profile.tx_w * air_h + profile.rx_w * rx_h + profile.idle_w * idle_h
    data_bounded = ceiling is not None or upper_bound is not False
    if budget.control is not None and data_bounded:  # DATA's bound with the control's
        ceiling = _with_control_bound(ceiling or budget)
    return RadioReport(
        profile,
        budget.drone_to_base,
        packets_h + control_packets_h,
        air_h,
        rx_h,
        energy,
        _costs(budget, data_h),
        upper_bound,
        radio_report(profile, ceiling, True) if ceiling else None,
        calibration,
        control_h,
        budget.control is not None,
    )


def _with_control_bound(budget: LinkBudget) -> LinkBudget:
    """``budget`` with its control traffic's bound in place of its estimate."""
    return replace(
        budget,
        drone_to_base=budget.data_to_base + budget.control_bound_bytes_per_s,
        control=None,
        control_about=budget.control_at_most,
        control_at_most=(),
    )


def _scale(budget: LinkBudget) -> float:
    """Walked packets to an hour."""
    return HOUR_S / budget.span_s if budget.span_s > 0 else 0.0


def _data_air(profile: RadioProfile, budget: LinkBudget) -> tuple[float, float]:
    """The DATA packets' air time and radio packets per hour."""
    air, packets = 0.0, 0
    for size in budget.packet_sizes:
        a, n = profile.packet_s(size)
        air += a
        packets += n
    scale = _scale(budget)
    return air * scale, packets * scale


def _control_air(
    profile: RadioProfile, control: tuple[tuple[int, float], ...]
) -> tuple[float, float]:
    """Control packets' (wire bytes, per hour) air time and radio packets per hour."""
    air, packets = 0.0, 0.0
    for size, per_hour in control:
        a, n = profile.packet_s(size)
        air += a * per_hour
        packets += n * per_hour
    return air, packets


def _costs(budget: LinkBudget, air_h: float) -> tuple[SubscriptionCost, ...]:
    """Each subscription's share of the DATA's bytes/s and air time."""
    total = sum(rate for rate, _ in budget.streams)
    if total <= 0:
        return ()
    by_name: dict[str, list[float]] = {}
    for rate, subs in budget.streams:
        if not subs:
            continue
        share = rate / total / len(subs)
        for s in subs:
            entry = by_name.setdefault(s, [0.0, 0.0])
            entry[0] += share * budget.data_to_base
            entry[1] += share * air_h
    costs = [SubscriptionCost(n, b, a) for n, (b, a) in by_name.items()]
    return tuple(sorted(costs, key=lambda c: (-c.air_s_per_hour, c.name)))
