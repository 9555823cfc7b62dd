"""A deployed model applied in place (issue 39, item 5), process by process:
the on-board model file's hand-over and answers (modd.onboard), modd-sensors'
readers (only the changed ones stop and start; a missing device is said), and
modd-mavlink's mapped variables (changed between two reads). The devices are
pseudo-terminals; the publishers are recorders."""

from __future__ import annotations

import contextlib
import os
import threading
import time
import tty
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from modd import onboard
from modd.mavlink.bridge import Bridge
from modd.mavlink.mapping import BridgePlan, FieldMapping, PublisherPlan
from modd.mavlink.reload import replan
from modd.sensors.plan import Device, Mapping, SensorPlan
from modd.sensors.reload import apply_plans, linked_device
from modd.sensors.run import Runner


class Recorder:
    def __init__(self) -> None:
        self.declared: dict[str, str] = {}
        self.samples: list[tuple[str, Any]] = []

    def declare(self, topic: str, vtype: str) -> None:
        self.declared[topic] = vtype

    def publish(self, topic: str, timestamp_ns: int, value: Any) -> bool:
        self.samples.append((topic, value))
        return True

    def flush(self, timeout: float = 5.0) -> bool:
        return True

    def close(self, timeout: float = 2.0) -> None:
        pass


# -- the hand-over ---------------------------------------------------------------------------


def test_the_hand_over_is_seen_once_and_answered_by_digest(tmp_path: Path) -> None:
    path = tmp_path / "model.json"
    first = onboard.hand_over(path, {"drone": {"name": "a"}})
    watch = onboard.ModelWatch(path)
    assert watch.digest == first and watch.poll() is None
    onboard.write_result(path, "sensors", first, {"ok": True})
    second = onboard.hand_over(path, {"drone": {"name": "b"}})
    assert second != first and watch.poll() is not None and watch.digest == second
    assert watch.poll() is None  # said once
    # no answer for the new model: said after the wait, not hung on
    start = time.monotonic()
    late = onboard.wait_results(path, second, 0.3)
    assert 0.3 <= time.monotonic() - start < 1.0
    assert late == {
        "sensors": {"process": "sensors", "ok": False, "problem": "no answer within 0.3 s"}
    }
    answer = threading.Timer(
        0.1, onboard.write_result, (path, "sensors", second, {"ok": True, "sensors": []})
    )
    answer.start()
    got = onboard.wait_results(path, second, 2.0)
    assert got["sensors"]["ok"] is True and got["sensors"]["digest"] == second


def test_a_handed_over_model_is_taken_as_validated_until_edited(tmp_path: Path) -> None:
    path = tmp_path / "model.json"
    applied = onboard.hand_over(path, {"drone": {"name": "a"}})
    assert onboard.validated(path, applied) == {"drone": {"name": "a"}}
    path.write_text('{"drone": {"name": "edited by hand"}}')
    edited = onboard.digest(path.read_bytes())
    assert onboard.validated(path, edited) is None and onboard.validated(path, applied) is None


def test_an_oversized_or_damaged_answer_file_is_left_out(tmp_path: Path) -> None:
    path = tmp_path / "model.json"
    onboard.results_dir(path).mkdir()
    (onboard.results_dir(path) / "sensors.json").write_text("{not json")
    assert onboard.read_results(path) == {}


# -- modd-sensors ------------------------------------------------------------------------------


@contextlib.contextmanager
def pty_at(link: Path) -> Iterator[int]:
    master, slave = os.openpty()
    tty.setraw(slave)
    os.symlink(os.ttyname(slave), link)
    try:
        yield master
    finally:
        os.close(master)
        os.close(slave)


def _nmea(name: str, path: Path, sentence: str = "DBT", field: str = "depth_meters") -> SensorPlan:
    mapping = Mapping(f"usv.{name}.depth", "float32", "nav", (sentence, field))
    return SensorPlan(name, "nmea", Device(str(path)), (mapping,))


def test_only_the_changed_readers_stop_and_start(tmp_path: Path) -> None:
    lines: list[str] = []
    sinks: dict[str, Recorder] = {"nav": Recorder()}
    a, b = _nmea("a", tmp_path / "a"), _nmea("b", tmp_path / "b")
    with pty_at(tmp_path / "a"), pty_at(tmp_path / "b"), pty_at(tmp_path / "c"):
        runner = Runner([a, b], sinks, lines.append)
        stop = threading.Event()
        loop = threading.Thread(target=runner.run, args=(stop, 0.05))
        loop.start()
        try:
            kept = runner.sensors[0]
            b2 = replace(b, mappings=(replace(b.mappings[0], topic="usv.b.depth2"),))
            c, gone = _nmea("c", tmp_path / "c"), _nmea("d", tmp_path / "nothing-here")
            result = apply_plans(
                runner, [a, b2, c, gone], lambda n: sinks.setdefault(n, Recorder())
            )
            by = {r["sensor"]: r for r in result["sensors"]}
            assert by["a"] == {"sensor": "a", "action": "unchanged", "ok": True, "state": "open"}
            assert by["b"]["action"] == "restarted" and by["b"]["state"] == "open"
            assert by["c"]["action"] == "started" and by["c"]["ok"]
            assert by["d"]["problem"] == f"device {tmp_path / 'nothing-here'} missing"
            assert result["ok"] is False
            assert runner.sensors[0] is kept and kept.thread.is_alive()
            assert sinks["nav"].declared["usv.b.depth2"] == "float32"
            old = {s.plan.name: s for s in runner.sensors}
            result = apply_plans(runner, [a], lambda n: sinks.setdefault(n, Recorder()))
            assert sorted(r["action"] for r in result["sensors"]) == [
                "stopped",
                "stopped",
                "stopped",
                "unchanged",
            ]
            assert result["ok"] is True
            assert not any(old[n].thread.is_alive() for n in ("b", "c", "d"))
            assert [s.plan.name for s in runner.sensors] == ["a"]
        finally:
            stop.set()
            loop.join(5)


def test_a_simulated_runs_device_link_wins_over_the_models_path(tmp_path: Path) -> None:
    (tmp_path / "gnss").symlink_to("/dev/null")
    plan = _nmea("gnss", Path("/dev/ttyUSB7"))
    assert linked_device(plan, tmp_path).device.path == str(tmp_path / "gnss")
    assert linked_device(plan, None) is plan
    assert (
        linked_device(_nmea("echo", Path("/dev/ttyUSB8")), tmp_path).device.path == "/dev/ttyUSB8"
    )


# -- modd-mavlink ------------------------------------------------------------------------------


class NoTransport:
    datagram = True

    def write(self, data: bytes) -> None:
        pass


def _plan(*mappings: FieldMapping) -> BridgePlan:
    plan = BridgePlan(publishers=[PublisherPlan("nav", 0.1, mappings)])
    for m in mappings:
        plan.by_message.setdefault(m.message, []).append(("nav", m))
        plan.intervals_us[m.message] = 100_000
    return plan


def test_the_bridge_changes_its_variables_in_place() -> None:
    yaw = FieldMapping("usv.ap.yaw", "float32", "ATTITUDE", "yaw")
    lat = FieldMapping("usv.ap.lat", "float64", "GLOBAL_POSITION_INT", "lat", 1e-7)
    sinks: dict[str, Recorder] = {"nav": Recorder()}
    bridge = Bridge(_plan(yaw, lat), NoTransport(), sinks, log=lambda _: None)  # type: ignore[arg-type]
    pitch = FieldMapping("usv.ap.pitch", "float32", "ATTITUDE", "pitch")
    lat2 = replace(lat, scale=1e-6)
    result = replan(bridge, _plan(yaw, pitch, lat2), lambda n: sinks.setdefault(n, Recorder()))
    assert result["added"] == ["usv.ap.pitch"] and result["changed"] == ["usv.ap.lat"]
    assert result["removed"] == [] and result["ok"] is True
    assert [m.topic for _, m in bridge.plan.by_message["ATTITUDE"]] == [
        "usv.ap.yaw",
        "usv.ap.pitch",
    ]
    assert sinks["nav"].declared["usv.ap.pitch"] == "float32"
    result = replan(bridge, _plan(yaw), lambda n: sinks.setdefault(n, Recorder()))
    assert result["removed"] == ["usv.ap.lat", "usv.ap.pitch"]
    assert bridge.autopilot.intervals_us == {"ATTITUDE": 100_000}


@pytest.mark.parametrize("text", ["{", '{"drone": 3}'])
def test_a_damaged_model_file_is_refused_by_the_sensors_check(tmp_path: Path, text: str) -> None:
    from modd.sensors.check import model_or_why

    path = tmp_path / "model.json"
    path.write_text(text)
    model, why = model_or_why(str(path))
    assert model is None and why


def test_onboards_payload_is_the_hand_overs_bytes_and_its_answers_are_bounded(
    tmp_path: Path,
) -> None:
    """ONBOARD carries the bytes hand_over writes (one zstd frame, its size in the
    header, read back with zstandard as the oracle); ONBOARD_ACK's answers are read
    within a bound and must be a JSON object."""
    import zstandard

    model = {"drone": {"name": "usv", "sensors": []}, "subscribers": []}
    path = tmp_path / "model.json"
    onboard.hand_over(path, model)
    packed = onboard.pack(model)
    assert zstandard.ZstdDecompressor().decompress(packed) == path.read_bytes()
    assert zstandard.get_frame_parameters(packed).content_size == len(path.read_bytes())
    answers = zstandard.ZstdCompressor(write_content_size=True).compress(
        b'{"sensors": {"ok": true}}'
    )
    assert onboard.unpack_answers(answers, 1024) == {"sensors": {"ok": True}}
    bomb = zstandard.ZstdCompressor().compress(b'{"x": "' + b"a" * 100_000 + b'"}')
    with pytest.raises(ValueError, match="unreadable"):
        onboard.unpack_answers(bomb, 1024)  # above the bound: refused, not decompressed
    with pytest.raises(ValueError, match="not a JSON object"):
        onboard.unpack_answers(zstandard.ZstdCompressor().compress(b"[1]"), 1024)
