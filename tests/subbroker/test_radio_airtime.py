"""The planner's air time per hour against the radio emulator's measurement
(modd-radio with a profile, airtime.py): scenario 1 over serial through a
SiK profile, real processes (the C++ PubBroker, the publisher load, the
SubBroker); the relay runs in this process so that every packet it carried
is seen. The oracle is the DATA frames the PubBroker actually sent, timed
by the relay, each at the profile's air time."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from modd.link.datagram import DGRAM_DATA
from modd.link.serialframe import cobs_decode
from modd.radio import relay
from modd.radio.airtime import AirtimeChannel
from modd_plan import make_plan
from modd_plan.radio import RadioProfile
from radio_harness import through_profile
from subbroker_harness import model_copy

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

LOAD_S = 24.0


class _Recording(AirtimeChannel):
    """Records (time, size, air time) of every packet it transmits."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.sent: list[tuple[float, bytes, float]] = []

    def offer(self, packet: bytes, now: float) -> float | None:
        before = self.air_s
        at = super().offer(packet, now)
        self.sent.append((now, packet, self.air_s - before))
        return at


def _is_data(packet: bytes) -> bool:
    try:
        return packet.endswith(b"\x00") and cobs_decode(packet.rstrip(b"\x00"))[0] == DGRAM_DATA
    except (ValueError, IndexError):
        return False


def _measure(
    tmp: Path, model: dict[str, Any], load_s: float, signal: str = "uniform"
) -> tuple[list[int], float, float]:
    """The model over serial through its ``link.radio`` profile: the DATA
    packets' sizes, air time and energy per hour, measured between the first
    and the last DATA packet (every packet after the first; receiving the base
    station's packets and idle over the same span)."""
    base, base_path = relay.open_pty_pair()
    drone, drone_path = relay.open_pty_pair()
    model["link"]["device"] = base_path
    model_path = tmp / "model.json"
    model_path.write_text(json.dumps(model))
    profile = RadioProfile.of(model["link"]["radio"])
    up, down = through_profile(
        tmp, model_path, (base, base_path, drone, drone_path), profile, load_s, signal
    )
    assert isinstance(down, _Recording) and isinstance(up, _Recording)
    assert not down.dropped, down.summary()  # a plan that fits: nothing refused
    data = [(t, len(packet), a) for t, packet, a in down.sent if _is_data(packet)]
    assert len(data) > 12, down.summary()
    span = data[-1][0] - data[0][0]
    air = sum(a for _, _, a in data[1:]) * 3600 / span
    rx = sum(a for t, _, a in up.sent if data[0][0] <= t <= data[-1][0]) * 3600 / span
    energy = profile.tx_w * air + profile.rx_w * rx + profile.idle_w * (3600 - air - rx)
    return [n for _, n, _ in data], air, energy


# SiK: no duty-cycle limit; LoRa SF7 at a 20 % limit: the plan fits (502 s of
# air per hour), the radio's silence after each packet (4 x 0.17 s) ends
# before the next one (every 1.25 s)
PROFILES = {"sik": {"kind": "sik"}, "lora": {"kind": "lora", "dutyCycle": "0.2"}}


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_planned_air_time_is_what_the_emulator_measures(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(relay, "AirtimeChannel", _Recording)
    model = json.loads(model_copy(tmp_path, "scenario1.modd").read_text())
    model["link"] = {"transport": "serial", "device": "", "radio": PROFILES[name]}
    predicted = make_plan(model).radio
    assert predicted is not None and predicted.fits
    _, air, energy = _measure(tmp_path, model, LOAD_S)
    print(f"{name}: air {air:.3f} s/h measured, {predicted.air_s_per_hour:.3f} planned")
    assert air == pytest.approx(predicted.air_s_per_hour, rel=0.05)
    print(f"{name}: energy {energy:.3f} J/h measured, {predicted.energy_j_per_hour:.3f} planned")
    assert energy == pytest.approx(predicted.energy_j_per_hour, rel=0.05)


def _at_resolution(tmp: Path, bound: float, delay: str, radio: dict[str, Any]) -> dict[str, Any]:
    """Scenario 1 over serial at 0.01 on every variable, declared in +-bound."""
    model: dict[str, Any] = json.loads(model_copy(tmp, "scenario1.modd").read_text())
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01, validMin=-bound, validMax=bound)
    model["link"] = {"transport": "serial", "device": "", "acceptedDelayS": delay, "radio": radio}
    return model


# Declared resolutions (issue 34): 0.01 on every accelerometer variable over its
# declared range of +-10, the load uniform in that range; a 0.2 s accepted delay
# under the 0.25 s periods puts one window in each datagram, so every value is
# absolute and the planner's figures are upper bounds ("at most", resolution.py).
# LoRa at a 50 % limit: the plan fits (about 3,100 packets of 26 B per hour).
BOUNDED = {
    "sik": {"kind": "sik"},
    "wifi": {"kind": "wifi"},
    "lora": {"kind": "lora", "dutyCycle": "0.5"},
}
BOUNDED_LOAD_S = 12.0  # 48 datagrams


@pytest.mark.parametrize("name", sorted(BOUNDED))
def test_planned_air_time_with_resolutions_bounds_the_emulators(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(relay, "AirtimeChannel", _Recording)
    model = _at_resolution(tmp_path, 10, "0.2", BOUNDED[name])
    plan = make_plan(model)
    predicted = plan.radio
    assert predicted is not None and predicted.fits and predicted.upper_bound is True
    assert plan.budget is not None
    sizes, air, energy = _measure(tmp_path, model, BOUNDED_LOAD_S)
    # every datagram within the planner's largest: the values inside their range
    assert max(sizes) <= max(plan.budget.packet_sizes)
    print(
        f"{name}: air {air:.3f} s/h measured, at most {predicted.air_s_per_hour:.3f} planned; "
        f"energy {energy:.3f} J/h measured, at most {predicted.energy_j_per_hour:.3f} planned"
    )
    # a bound (1 % for the span's timing on a loaded machine), and a close one
    # for values that mostly need the bytes their range allows (the MIN, MAX
    # and most AVERAGEs of 6 samples uniform in +-10 are 64 steps or more from 0)
    assert predicted.air_s_per_hour * 0.95 <= air <= predicted.air_s_per_hour * 1.01
    assert predicted.energy_j_per_hour * 0.95 <= energy <= predicted.energy_j_per_hour * 1.01


# Calibrated by an archive (modd plan --calibrate): scenario 1 at 0.01 m/s^2
# over +-20 declared, the wave load, a 0.5 s accepted delay (2-3 slots a
# datagram: absolute values and deltas). Each profile's run is measured
# against the plan calibrated by the archive of ANOTHER run (the next
# profile's: same load generator, another process); three runs in all.
# LoRa at a 50 % limit: the plan fits.
CALIBRATED = {
    "lora": {"kind": "lora", "dutyCycle": "0.5"},
    "sik": {"kind": "sik"},
    "wifi": {"kind": "wifi"},
}
CALIBRATED_LOAD_S = 15.0  # about 20 datagrams


def _archive_samples(archive_dir: Path) -> dict[str, Any]:
    from modd.dataset.samples import read_samples

    files = sorted(archive_dir.glob("*.mcap"))
    assert files, f"no archive in {archive_dir}"
    out: dict[str, Any] = {}
    for f in files:  # one file a run here; several would follow each other in time
        for topic, (stamps, values) in read_samples(f, TOPICS).items():
            got = out.setdefault(topic, ([], []))
            got[0].extend(stamps)
            got[1].extend(values)
    return out


TOPICS = [f"usv.accelerometer.accel_{a}" for a in "xyz"]


def test_planned_air_time_calibrated_by_another_run_is_the_emulators(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from modd_plan.calibration import Calibration

    monkeypatch.setattr(relay, "AirtimeChannel", _Recording)
    runs: dict[str, tuple[dict[str, Any], float, float, dict[str, Any]]] = {}
    for name, radio in CALIBRATED.items():
        run = tmp_path / name
        run.mkdir()
        model = _at_resolution(run, 20, "0.5", radio)
        _, air, energy = _measure(run, model, CALIBRATED_LOAD_S, "wave")
        runs[name] = (model, air, energy, _archive_samples(run / "archive"))
    names = list(CALIBRATED)
    for i, name in enumerate(names):
        model, air, energy, _ = runs[name]
        other = names[(i + 1) % len(names)]
        plan = make_plan(model, calibration=Calibration(f"{other}.mcap", runs[other][3]))
        bound = make_plan(model).radio
        predicted = plan.radio
        assert predicted is not None and bound is not None and predicted.fits
        assert predicted.figures == "estimate" and predicted.calibration is not None
        assert not predicted.calibration.missing and len(predicted.calibration.sizes) == 4
        print(
            f"{name}: air {air:.3f} s/h measured, {predicted.air_s_per_hour:.3f} planned "
            f"calibrated by {other}'s run ({bound.at_most}{bound.air_s_per_hour:.3f} without); "
            f"energy {energy:.3f} J/h measured, {predicted.energy_j_per_hour:.3f} planned "
            f"({bound.energy_j_per_hour:.3f} without)"
        )
        assert air == pytest.approx(predicted.air_s_per_hour, rel=0.05)
        assert energy == pytest.approx(predicted.energy_j_per_hour, rel=0.05)
