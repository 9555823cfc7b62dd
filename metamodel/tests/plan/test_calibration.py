"""The planner calibrated by an archive's samples (modd_plan.calibration):
each stream's windows recomputed from the samples and their quantised sizes
against the runtime's link codec (``modd.link.codec.put_number``, the bytes
the PubBroker's peer decodes: an oracle the planner does not share), and
what a calibration changes in a plan (and what it must not)."""

from __future__ import annotations

import copy
import math
import random
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from modd.link.codec import put_number
from modd_model import load_model
from modd_plan import make_plan
from modd_plan.calibration import Calibration, Series

SCENARIO1 = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "scenario1.modd"
TOPICS = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
NS = 1_000_000_000
SAMPLE_NS = 40_000_000  # 25 Hz


def _series(signal: Any, seconds: float, seed: int = 1) -> Series:
    rng = random.Random(seed)
    stamps = [k * SAMPLE_NS + rng.randrange(1000) for k in range(int(seconds * NS / SAMPLE_NS))]
    return stamps, [float(signal(t / NS, rng)) for t in stamps]


def _wave(t: float, rng: random.Random) -> float:
    return math.sin(2 * math.pi * t / 8) + rng.uniform(-0.01, 0.01)


def _uniform(_t: float, rng: random.Random) -> float:
    return rng.uniform(-20, 20)


def _high(_t: float, rng: random.Random) -> float:
    return rng.uniform(10, 20)


def _oracle_windows(series: Series, aggregation: str, period_s: float) -> list[list[float]]:
    """Windows from the first sample, grouped by a dict, aggregated by hand."""
    stamps, values = series
    groups: dict[int, list[float]] = {}
    for t, x in zip(stamps, values, strict=True):
        groups.setdefault(int((t - stamps[0]) // round(period_s * NS)), []).append(x)
    out = []
    for _, xs in sorted(groups.items())[:-1]:  # the last one, cut by the series' end
        one = {
            "MIN": min(xs),
            "MAX": max(xs),
            "FIRST": xs[0],
            "LAST": xs[-1],
            "SUM": math.fsum(xs),
            "AVERAGE": math.fsum(xs) / len(xs),
        }
        out.append(list(xs) if aggregation == "ALL" else [one[aggregation]])
    return out


def _codec_sizes(windows: list[list[float]], r: float) -> tuple[float, float]:
    """Mean bytes of each window's first value coded alone, and of every
    other value coded in one chain (the codec's put_number)."""
    firsts = []
    for w in windows:
        b = bytearray()
        put_number(b, {}, 0, w[0], r)
        firsts.append(len(b))
    values = [x for w in windows for x in w]
    chain = bytearray()
    links: dict[int, int] = {}
    put_number(chain, links, 0, values[0], r)
    first = len(chain)
    for x in values[1:]:
        put_number(chain, links, 0, x, r)
    return sum(firsts) / len(firsts), (len(chain) - first) / (len(values) - 1)


@pytest.mark.parametrize("aggregation", ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "SUM", "ALL"])
@pytest.mark.parametrize("signal", [_wave, _uniform], ids=["wave", "uniform"])
@pytest.mark.parametrize("r", [0.01, 0.5])
def test_sizes_are_the_codecs(aggregation: str, signal: Any, r: float) -> None:
    series = _series(signal, 60)
    got = Calibration("a.mcap", {"t": series}).sizes("t", aggregation, Fraction(1, 4), r)
    windows = _oracle_windows(series, aggregation, 0.25)
    assert got is not None and got.windows == len(windows) == 239
    absolute, delta = _codec_sizes(windows, r)
    assert float(got.absolute) == pytest.approx(absolute, abs=0.005)
    assert float(got.delta) == pytest.approx(delta, abs=0.005)  # means to 1/100 B


def test_escaped_values_cost_nine_bytes_and_keep_the_chain() -> None:
    stamps = [k * NS for k in range(7)]
    values = [0.5, math.nan, 0.52, 1e300, 0.0, 0.01, 0.0]  # the last window: cut
    got = Calibration("a.mcap", {"t": (stamps, values)}).sizes("t", "LAST", Fraction(1), 0.01)
    absolute, delta = _codec_sizes([[x] for x in values[:-1]], 0.01)
    assert got is not None
    assert (float(got.absolute), float(got.delta)) == pytest.approx((absolute, delta), abs=1e-3)
    assert float(got.absolute) == pytest.approx((1 + 9 + 1 + 9 + 1 + 1) / 6, abs=1e-3)


def test_only_the_first_windows_are_used() -> None:
    calm = _series(lambda t, rng: 0.0, 100)
    loud = _series(_uniform, 100)
    stamps = list(calm[0]) + [t + 100 * NS for t in loud[0]]
    both = Calibration("a.mcap", {"t": (stamps, list(calm[1]) + list(loud[1]))}, limit=100)
    got = both.sizes("t", "AVERAGE", Fraction(1), 0.01)
    assert got is not None and got.windows == 100 and got.absolute == 1  # the calm ones only


def _lora_model(lo: float, hi: float) -> dict[str, Any]:
    """Scenario 1 at 0.01 m/s^2 over a LoRa link, every period 8 s and an
    accepted delay of 1 s: one window of each stream per datagram, every
    value absolute, the figures an upper bound without calibration."""
    model = copy.deepcopy(load_model(SCENARIO1))
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01, validMin=lo, validMax=hi)
    for s in model["subscribers"]:
        s["periodS"] = "8.0"
    model["link"] = {
        "transport": "serial",
        "device": "/dev/null",
        "acceptedDelayS": "1",
        "radio": {"kind": "lora"},
    }
    return model


def test_a_signal_near_zero_costs_less_than_one_filling_the_range() -> None:
    model = _lora_model(-20, 20)
    bound = make_plan(model)
    calm = Calibration("calm.mcap", {t: _series(_wave, 120, i) for i, t in enumerate(TOPICS)})
    full = Calibration("full.mcap", {t: _series(_high, 120, i) for i, t in enumerate(TOPICS)})
    a, b = make_plan(model, calibration=calm), make_plan(model, calibration=full)
    assert bound.radio and a.radio and b.radio and a.budget and b.budget
    assert bound.radio.upper_bound is True  # the DATA's (with control: "estimate")
    assert a.radio.figures == b.radio.figures == "estimate"
    # the 8 s AVERAGEs of an 8 s wave are ~0 (1 B), its MIN/MAX ~+-1 (2 B):
    # 4 values, each with the count of an AVERAGE: 22 B a datagram on the
    # serial line; a load in [10, 20] puts every value past 64 steps (2 B), as
    # the range's bound assumes
    sizes = {k: v for k, v in (a.radio.calibration.sizes if a.radio.calibration else ())}
    assert [float(v.absolute) for v in sizes.values()] == [1.0, 1.0, 2.0, 2.0]
    assert set(a.budget.packet_sizes) == {22} and set(b.budget.packet_sizes) == {24}
    assert bound.budget and set(bound.budget.packet_sizes) == {24}
    assert a.radio.air_s_per_hour < b.radio.air_s_per_hour == bound.radio.air_s_per_hour
    doc = a.to_json()["radio"]
    assert doc["calibrated_from"] == "calm.mcap"
    assert doc["calibration"]["not_calibrated"] == []
    assert {s["stream"]: s["absolute_bytes"] for s in doc["calibration"]["streams"]} == {
        k: float(v.absolute) for k, v in sizes.items()
    }


def test_a_topic_without_samples_keeps_the_bound_and_is_named() -> None:
    model = _lora_model(-20, 20)
    bound = make_plan(model)
    part = Calibration("x.mcap", {TOPICS[0]: _series(_wave, 60)})
    plan = make_plan(model, calibration=part)
    assert plan.radio and plan.radio.calibration and bound.radio
    doc = plan.to_json()["radio"]
    missing = doc["calibration"]["not_calibrated"]
    assert missing and all(not k.startswith(TOPICS[0]) for k in missing)
    assert [s["stream"].split("/")[0] for s in doc["calibration"]["streams"]] == [TOPICS[0]]
    assert plan.budget and bound.budget  # accel_x's AVERAGE ~0: 1 B instead of 2
    assert set(bound.budget.packet_sizes) == {24} and set(plan.budget.packet_sizes) <= {23, 24}
    assert sum(plan.budget.packet_sizes) < sum(bound.budget.packet_sizes)


def test_an_archive_without_the_models_topics_changes_nothing_but_says_so() -> None:
    model = _lora_model(-20, 20)
    model["link"]["radio"]["dutyCycle"] = "0.02"  # fits: no proposals
    none = make_plan(model, calibration=Calibration("empty.mcap", {})).to_json()
    plain = make_plan(model).to_json()
    radio = none.pop("radio")
    assert radio.pop("calibrated_from") == "empty.mcap"
    assert len(radio.pop("calibration")["not_calibrated"]) == 4
    assert {**none, "radio": radio} == plain


def test_a_plan_without_resolutions_is_unchanged_by_a_calibration() -> None:
    model = _lora_model(-20, 20)
    for v in model["drone"]["sensors"][0]["variables"]:
        del v["resolution"]
    cal = Calibration("a.mcap", {t: _series(_wave, 60) for t in TOPICS})
    assert make_plan(model, calibration=cal).to_json() == make_plan(model).to_json()


def test_proposals_carry_the_calibration() -> None:
    model = _lora_model(-20, 20)
    for s in model["subscribers"]:
        s["periodS"] = {"sub_1": "2.0", "sub_2": "2.0"}.get(s["name"], "0.25")
    cal = Calibration("calm.mcap", {t: _series(_wave, 60, i) for i, t in enumerate(TOPICS)})
    plan = make_plan(model, calibration=cal)
    assert plan.radio is not None and not plan.radio.fits and plan.proposals
    for p in plan.to_json()["radio"]["proposals"]:
        assert p["calibrated_from"] == "calm.mcap" and p["figures"] == "estimate"
    assert all("calibrated_from" not in p for p in make_plan(model).to_json()["radio"]["proposals"])


def test_calibrated_rates_are_over_whole_datagrams() -> None:
    """0.25 s slots and a 0.5 s accepted delay: datagrams of 3 slots, one
    every 0.75 s, 4,800 an hour. The walk of 20 accepted delays (40 slots)
    ends inside a datagram: both plans walk on to the end of that datagram
    and count whole ones (counting the cut one made 14 packets of 10 s,
    5,040 an hour: 5 % over the link's steady state)."""
    model = _lora_model(-20, 20)
    for s in model["subscribers"]:
        s["periodS"] = "0.25"
    model["link"].update(acceptedDelayS="0.5", radio={"kind": "sik"})
    cal = Calibration("calm.mcap", {t: _series(_wave, 60, i) for i, t in enumerate(TOPICS)})
    calibrated, plain = make_plan(model, calibration=cal).radio, make_plan(model).radio
    assert calibrated is not None and plain is not None
    # and 120 PONGs and 60 STATUS an hour (control.py)
    assert calibrated.packets_per_hour == pytest.approx(3600 / 0.75 + 180)
    assert plain.packets_per_hour == pytest.approx(3600 / 0.75 + 180)
