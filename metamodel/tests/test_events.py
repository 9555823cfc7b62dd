"""The reference definition of event subscriptions (modd_contracts.events):
hand-worked signals, and properties checked sample by sample against a
restatement of the definition (each event leaves its deadband or its
hysteresis band; each other sample does not); the vectors the C++ detector is
tested with are what the generator writes."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from modd_contracts.events import EventSpec, EventWindow, implied, windows
from modd_contracts.link_wire_gen import MAX_EVENTS, Crossing, DeadbandMode, EventKind

VECTORS = Path(__file__).resolve().parents[2] / "contracts" / "vectors"
ON, TH = EventKind.ON_CHANGE, EventKind.THRESHOLD


def _timed(values: list[float], step: int = 10) -> list[tuple[int, float]]:
    return [(k * step, x) for k, x in enumerate(values)]


def test_the_generator_reproduces_the_committed_vectors() -> None:
    spec = importlib.util.spec_from_file_location("gen_events", VECTORS / "gen_events.py")
    assert spec and spec.loader
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    assert gen.text() == (VECTORS / "events.json").read_text(encoding="utf-8")


def test_on_change_steps_by_hand() -> None:
    samples = _timed([4.0, 4.0, 4.3, 4.6, 6.0, 5.9, 6.0, 3.0])
    assert implied(EventSpec(ON, 10, deadband=0.5), samples) == [
        (0, 4.0),
        (30, 4.6),
        (40, 6.0),
        (70, 3.0),
    ]
    # exactly the deadband away is no change (more than d is)
    assert implied(EventSpec(ON, 10, deadband=1.0), _timed([1.0, 2.0, 2.5])) == [
        (0, 1.0),
        (20, 2.5),
    ]
    rel = EventSpec(ON, 10, deadband=0.1, mode=DeadbandMode.RELATIVE)
    assert implied(rel, _timed([100.0, 109.0, 111.0, 121.0, 123.0])) == [
        (0, 100.0),
        (20, 111.0),
        (40, 123.0),
    ]


def test_threshold_by_hand() -> None:
    values = [4.0, 5.1, 4.9, 5.6, 4.7, 4.4, 5.4, 5.6]
    both = EventSpec(TH, 10, level=5.0, hysteresis=0.5)
    assert implied(both, _timed(values)) == [(30, 5.6), (50, 4.4), (70, 5.6)]
    up = EventSpec(TH, 10, level=5.0, hysteresis=0.5, crossing=Crossing.UP)
    assert implied(up, _timed(values)) == [(30, 5.6), (70, 5.6)]
    down = EventSpec(TH, 10, level=5.0, crossing=Crossing.DOWN)  # no hysteresis: at the level
    assert implied(down, _timed([6.0, 5.0, 4.99, 5.0, 5.01, 4.0])) == [(20, 4.99), (50, 4.0)]
    # the first sample sets the side: starting below is no DOWN event
    assert implied(down, _timed([3.0, 2.0])) == []


def _noisy(seed: int) -> list[tuple[int, float]]:
    rng = np.random.default_rng(seed)
    x = 5.0 + np.cumsum(rng.normal(0.0, 0.2, 400)) * 0.3 + rng.normal(0.0, 0.3, 400)
    return _timed([float(v) for v in x], step=25)


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("d", [0.0, 0.25, 1.0])
def test_on_change_keeps_every_other_sample_within_the_deadband(seed: int, d: float) -> None:
    samples = _noisy(seed)
    events = dict(implied(EventSpec(ON, 10, deadband=d), samples))
    last = None
    for t, x in samples:
        if t in events:
            assert last is None or abs(x - last) > d
            last = x
        else:
            assert last is not None and abs(x - last) <= d


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("h", [0.0, 0.2, 0.6])
def test_hysteresis_holds(seed: int, h: float) -> None:
    """Between two crossings the signal went past the band's other edge;
    UP and DOWN events alternate; UP-only events are the BOTH run's UPs."""
    samples = _noisy(seed)
    both = implied(EventSpec(TH, MAX_EVENTS, level=5.0, hysteresis=h), samples)
    ups = implied(EventSpec(TH, MAX_EVENTS, level=5.0, hysteresis=h, crossing=Crossing.UP), samples)
    assert ups == [e for e in both if e[1] > 5.0]
    sides = [x > 5.0 + h for _, x in both]
    assert all(a != b for a, b in zip(sides, sides[1:], strict=False))  # alternate
    assert all(x > 5.0 + h or x < 5.0 - h for _, x in both)
    times = [t for t, _ in both]
    for (t0, x0), t1 in zip(both, times[1:], strict=False):
        between = [x for t, x in samples if t0 < t < t1]
        assert all(5.0 - h <= x <= 5.0 + h or (x > 5.0) == (x0 > 5.0) for x in between)


def test_flapping_is_coalesced_and_counted() -> None:
    flapping = _timed([4.0 if k % 2 else 6.0 for k in range(100)])  # 10 samples a window of 100
    spec = EventSpec(TH, 3, level=5.0)
    wins = windows(spec, flapping, 0, 100)
    every = implied(spec, flapping)
    assert sum(len(w.events) + w.coalesced for w in wins) == len(every) == 99
    for j, w in enumerate(wins):
        mine = [e for e in every if j * 100 <= e[0] < (j + 1) * 100]
        assert len(w.events) == min(3, len(mine))
        assert w.events == [*mine[:2], mine[-1]] and w.coalesced == len(mine) - 3


def test_windows_skip_samples_before_the_epoch_and_keep_empty_ones() -> None:
    wins = windows(EventSpec(ON, 5), _timed([1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 3.0]), 10, 20)
    assert [w.events for w in wins] == [[(10, 1.0), (20, 2.0)], [], [(60, 3.0)]]
    assert not wins[1].present and EventWindow().coalesced == 0


@pytest.mark.parametrize(
    "bad",
    [
        {"max_events": 0},
        {"max_events": MAX_EVENTS + 1},
        {"deadband": -1.0},
        {"hysteresis": float("nan")},
    ],
)
def test_a_spec_out_of_bounds_is_refused(bad: dict[str, Any]) -> None:
    kwargs: dict[str, Any] = {"kind": ON, "max_events": 4, **bad}
    with pytest.raises(ValueError):
        EventSpec(**kwargs)


def test_vectors_hold_the_bound() -> None:
    doc = json.loads((VECTORS / "events.json").read_text(encoding="utf-8"))
    for case in doc["vectors"]:
        n = case["spec"]["maxEvents"]
        assert all(len(w["events"]) <= n for w in case["windows"]), case["name"]
