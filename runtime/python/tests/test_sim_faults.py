"""The simulator's injected faults (sim/faults.py): a spike and a flat line
reach what the simulated sensors publish, the file is read again when it
changes, and a bad file injects nothing (said once) while the sensors run on."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from modd.sim import sensors
from modd.sim.faults import FaultFile
from modd_model.query import Topic

TOPIC = "usv.ctd.water_temperature"


class FakePublisher:
    sent: list[tuple[str, int, Any]] = []

    def __init__(self, name: str, ingress: str) -> None:
        FakePublisher.sent = []

    def __enter__(self) -> FakePublisher:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def declare(self, name: str, type_: str) -> None:
        return None

    def publish(self, name: str, t_ns: int, value: Any) -> None:
        FakePublisher.sent.append((name, t_ns, value))


def test_a_spike_and_a_flat_line_reach_the_published_values(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sensors, "Publisher", FakePublisher)
    path = tmp_path / "faults.json"
    now = time.time()
    path.write_text(
        json.dumps(
            {
                "faults": [
                    {"topic": TOPIC, "kind": "spike", "at": now + 0.2, "offset": 100},
                    {"topic": TOPIC, "kind": "flat", "from": now + 0.5, "to": now + 0.9},
                ]
            }
        )
    )
    topic = Topic(TOPIC, "ctd", "water_temperature", "Cel", "float64", "p", None)
    stop = threading.Event()
    th = threading.Thread(
        target=sensors.run_publisher,
        args=("p", 0.02, [topic], "unix:/none", stop, 0, now, FaultFile(str(path))),
    )
    th.start()
    time.sleep(1.2)
    stop.set()
    th.join(5)
    values = [(t / 1e9, v) for _, t, v in FakePublisher.sent]
    spiked = [v for _, v in values if v > 50]
    assert len(spiked) == 1  # one sample, offset by 100 (the plume keeps it under 20)
    flat = {v for t, v in values if now + 0.5 <= t < now + 0.9}
    assert len(flat) == 1 and len([t for t, _ in values if now + 0.5 <= t < now + 0.9]) > 5
    after = [v for t, v in values if t >= now + 0.9]
    assert len(set(after)) > 1  # moving again


def test_the_file_is_read_again_and_a_bad_one_injects_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "faults.json"
    faults = FaultFile(str(path))
    assert faults.apply(TOPIC, 1.0, 2.0) == 2.0  # no file yet
    spike = {"topic": TOPIC, "kind": "spike", "at": 0, "offset": 1}
    path.write_text(json.dumps({"faults": [spike]}))
    assert faults.apply(TOPIC, 1.0, 2.0) == 3.0
    path.write_text('{"faults": [{"topic": "x", "kind": "wobble"}]}')
    assert faults.apply(TOPIC, 2.0, 2.0) == 2.0
    assert "faults[0]: kind 'wobble': spike or flat; no fault injected" in capsys.readouterr().err
    assert faults.apply(TOPIC, 3.0, True) is True  # a bool is never offset


def test_a_simulated_instrument_carries_the_faults_too(tmp_path: Path) -> None:
    from modd.sim.instruments import Instrument

    path = tmp_path / "faults.json"
    spike = {"topic": "usv.sounder.depth", "kind": "spike", "at": 10.0, "offset": 100}
    path.write_text(json.dumps({"faults": [spike]}))
    inst = object.__new__(Instrument)  # its values only: no device opened
    inst.start, inst.faults = 0.0, FaultFile(str(path))
    inst.signals = {"usv.sounder.depth": lambda t, p: 3.0}
    assert [inst.values(t)["usv.sounder.depth"] for t in (9.0, 10.0, 11.0)] == [3.0, 103.0, 3.0]
