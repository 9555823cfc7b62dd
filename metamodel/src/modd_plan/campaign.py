"""Plans of a campaign: one plan per drone, and the load of each shared
radio channel (modd_model.campaign).

Vehicles on one channel share its rate and its duty cycle: the sum of their
links' bytes per second (both ways, as each plan predicts them on the wire)
must fit the channel's ``rateBps``, and the sum of their radios' air time per
hour its ``dutyCycle``. A vehicle without a radio profile has no air time to
add: the duty-cycle check then says so rather than guess.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from modd_model.campaign import channel_members, expand
from modd_model.diagnostics import Diagnostic, pointer_join

from .plan import Plan, make_plan


@dataclass(frozen=True)
class ChannelLoad:
    """What the vehicles on one channel ask of it, summed."""

    name: str
    vehicles: tuple[str, ...]
    bytes_per_s: float
    rate_bps: int | None
    air_share: float | None  # None: a vehicle on it has no radio profile
    duty_cycle: float | None

    @property
    def errors(self) -> list[str]:
        out: list[str] = []
        who = ", ".join(self.vehicles)
        if self.rate_bps is not None and self.bytes_per_s > self.rate_bps:
            out.append(
                f"channel {self.name!r}: its vehicles ({who}) need {self.bytes_per_s:.1f} B/s "
                f"together, over its rate of {self.rate_bps} B/s"
            )
        if self.duty_cycle is not None and self.air_share is None:
            out.append(
                f"channel {self.name!r}: a vehicle on it has no radio profile "
                "(Link { radio = ...; }): its air time, hence the duty cycle, is unknown"
            )
        elif (
            self.duty_cycle is not None
            and self.air_share is not None
            and self.air_share > self.duty_cycle
        ):
            out.append(
                f"channel {self.name!r}: its vehicles ({who}) transmit "
                f"{self.air_share:.4%} of each hour together, over its duty cycle "
                f"of {self.duty_cycle:.4%}"
            )
        return out

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "vehicles": list(self.vehicles),
            "bytes_per_s": round(self.bytes_per_s, 3),
            "rate_bps": self.rate_bps,
            "air_share": None if self.air_share is None else round(self.air_share, 6),
            "duty_cycle": self.duty_cycle,
            "fits": not self.errors,
            "errors": self.errors,
        }


@dataclass(frozen=True)
class CampaignPlan:
    plans: dict[str, Plan]
    channels: tuple[ChannelLoad, ...]

    @property
    def fits(self) -> bool:
        return all(not c.errors for c in self.channels)

    def to_json(self) -> dict[str, Any]:
        return {
            "drones": {name: plan.to_json() for name, plan in self.plans.items()},
            "channels": [c.to_json() for c in self.channels],
            "fits": self.fits,
        }


def link_bytes_per_s(plan: Plan) -> float:
    """Both ways, on the declared transport's wire when it has a budget."""
    cost = plan.budget if plan.budget is not None else plan.link
    return cost.drone_to_base + cost.base_to_drone


def plan_campaign(model: Mapping[str, Any], **options: Any) -> CampaignPlan:
    """One plan per drone of a validated model (its one drone when it has no
    campaign), and the load of each shared channel. ``options``: make_plan's."""
    doc = dict(model)
    plans = {name: make_plan(m, **options) for name, m in expand(doc).items()}
    declared = {str(c["name"]): c for c in (doc.get("campaign") or {}).get("channels", [])}
    loads = []
    for name, members in channel_members(doc).items():
        chosen = [plans[v] for v in members]
        radios = [p.radio for p in chosen]
        air = None if any(r is None for r in radios) else sum(r.air_s_per_hour for r in radios if r)
        duty = declared[name].get("dutyCycle")
        loads.append(
            ChannelLoad(
                name=name,
                vehicles=tuple(members),
                bytes_per_s=sum(link_bytes_per_s(p) for p in chosen),
                rate_bps=declared[name].get("rateBps"),
                air_share=None if air is None else air / 3600,
                duty_cycle=None if duty is None else float(Fraction(duty)),
            )
        )
    return CampaignPlan(plans, tuple(loads))


def channel_diagnostics(model: Mapping[str, Any], **options: Any) -> list[Diagnostic]:
    """Each shared channel that cannot carry its vehicles together, located at the
    channel (``/campaign/channels/i``); none for a model without a campaign."""
    if not isinstance(model.get("campaign"), dict):
        return []
    names = [str(c["name"]) for c in model["campaign"].get("channels", [])]
    out = []
    for load in plan_campaign(model, **options).channels:
        where = pointer_join("campaign", "channels", names.index(load.name))
        out += [Diagnostic(error, where) for error in load.errors]
    return out
