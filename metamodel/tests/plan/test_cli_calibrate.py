"""``modd plan MODEL --calibrate ARCHIVE``: the archive written by the
official ``mcap`` writer (channels as the archive-record contract says), read
through the ``modd.samples`` entry point (the runtime's reader); the plan's
calibration is the one built from the same samples directly; bad archives
are located errors, never a traceback."""

from __future__ import annotations

import argparse
import io
import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from mcap.writer import CompressionType, Writer
from modd_model import load_model
from modd_plan import cli
from modd_plan.calibration import Calibration

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
TOPICS = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
NS = 1_000_000_000


def _samples(seconds: int = 40) -> dict[str, tuple[list[int], list[float]]]:
    out: dict[str, tuple[list[int], list[float]]] = {}
    for i, topic in enumerate(TOPICS):
        stamps = [1_700_000_000 * NS + k * 40_000_000 for k in range(seconds * 25)]
        out[topic] = (stamps, [math.sin(k / 50 + i) * (1 + i) for k in range(len(stamps))])
    return out


def write_archive(path: Path, samples: dict[str, tuple[list[int], list[float]]]) -> None:
    channel = next(
        c
        for c in json.loads((VECTORS / "archive_record.json").read_text())["channels"]
        if c["type"] == "float32"
    )
    with path.open("wb") as f:
        w = Writer(f, chunk_size=4096, compression=CompressionType.ZSTD)
        w.start(profile="", library="test")
        sid = w.register_schema(
            channel["schema_name"], channel["schema_encoding"], channel["schema_data"].encode()
        )
        for topic, (stamps, values) in samples.items():
            cid = w.register_channel(topic, channel["message_encoding"], sid, channel["metadata"])
            for t, x in zip(stamps, values, strict=True):
                data = b'{"value":' + repr(x).encode() + b"}"
                w.add_message(cid, log_time=t, data=data, publish_time=t)
        w.finish()  # type: ignore[no-untyped-call]


@pytest.fixture
def model_file(tmp_path: Path, scenarios_dir: Path) -> Path:
    model = load_model(scenarios_dir / "scenario1.modd")
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01, validMin=-20, validMax=20)
    model["link"] = {"transport": "serial", "device": "/dev/null", "radio": {"kind": "lora"}}
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model))
    return path


def _run(argv: list[str]) -> tuple[int, str]:
    parser = argparse.ArgumentParser(prog="modd")
    cli.register(parser.add_subparsers(dest="command", required=True))
    out = io.StringIO()
    return cli.run_plan(parser.parse_args(["plan", *argv]), out), out.getvalue()


def test_the_plan_is_calibrated_by_the_archive(model_file: Path, tmp_path: Path) -> None:
    samples = _samples()
    write_archive(tmp_path / "flight.mcap", samples)
    code, text = _run([str(model_file), "--json", "--calibrate", str(tmp_path / "flight.mcap")])
    assert code == 5  # scenario 1 is over LoRa's 1 %, calibrated or not
    radio = json.loads(text)["radio"]
    assert radio["calibrated_from"] == "flight.mcap" and radio["figures"] == "estimate"
    direct = Calibration("direct", samples)
    streams = radio["calibration"]["streams"]
    assert len(streams) == 4 and radio["calibration"]["not_calibrated"] == []
    for s in streams:
        topic, aggregation, period = s["stream"].split("/")
        want = direct.sizes(topic, aggregation, Fraction(period), 0.01)
        assert want is not None and s["windows"] == want.windows
        assert s["absolute_bytes"] == pytest.approx(float(want.absolute), abs=1e-3)
        assert s["delta_bytes"] == pytest.approx(float(want.delta), abs=1e-3)
    assert all(p["calibrated_from"] == "flight.mcap" for p in radio["proposals"])
    code, text = _run([str(model_file), "--calibrate", str(tmp_path / "flight.mcap")])
    assert "calibrated from flight.mcap (first 2000 windows of each stream)" in text


def test_a_partial_archive_names_the_streams_it_did_not_calibrate(
    model_file: Path, tmp_path: Path
) -> None:
    write_archive(tmp_path / "x.mcap", {TOPICS[0]: _samples()[TOPICS[0]]})
    code, text = _run([str(model_file), "--calibrate", str(tmp_path / "x.mcap")])
    assert code == 5
    line = next(x for x in text.splitlines() if x.startswith("  not calibrated"))
    assert TOPICS[2] + "/MIN/0.25" in line and TOPICS[0] not in line


def _error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    code, out = _run(argv)
    err = capsys.readouterr().err
    assert code == 1 and out == "" and "Traceback" not in err
    return err.strip()


def test_bad_archives_are_located_errors(
    model_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    m = str(model_file)
    missing = tmp_path / "none.mcap"
    assert _error(capsys, [m, "--calibrate", str(missing)]) == f"error: {missing}: no such archive"
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"not an archive at all")
    assert _error(capsys, [m, "--calibrate", str(garbage)]) == (
        f"error: {garbage}: offset 0: not an MCAP file (no MCAP magic)"
    )
    corrupt = tmp_path / "corrupt.mcap"
    write_archive(corrupt, _samples())
    data = bytearray(corrupt.read_bytes())
    data[200:260] = bytes(60)  # inside the first chunk
    corrupt.write_bytes(bytes(data))
    assert _error(capsys, [m, "--calibrate", str(corrupt)]).startswith(f"error: {corrupt}: offset ")
    other = tmp_path / "other.mcap"
    write_archive(other, {"boat.gps.lat": _samples()[TOPICS[0]]})
    assert _error(capsys, [m, "--calibrate", str(other)]) == (
        f"error: {other}: holds no sample of the model's topics ({', '.join(TOPICS)})"
    )


def test_without_a_reader_installed(
    model_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: Any
) -> None:
    import importlib.metadata

    monkeypatch.setattr(importlib.metadata, "entry_points", lambda **_: [])
    err = _error(capsys, [str(model_file), "--calibrate", str(tmp_path / "a.mcap")])
    assert "no archive reader is installed (entry-point group 'modd.samples')" in err


def test_a_long_archive_is_read_up_to_the_limit(tmp_path: Path) -> None:
    """The reader hands over the first ``limit`` samples of each topic and
    stops reading there: a damaged end past them is never reached."""
    from modd.dataset.samples import read_samples
    from modd_plan.calibration import CalibrationError

    samples = _samples(seconds=40)  # 1,000 samples a topic, in many 4 KiB chunks
    path = tmp_path / "long.mcap"
    write_archive(path, samples)
    data = bytearray(path.read_bytes())
    at = len(data) * 8 // 10  # a chunk near the end (the summary follows the chunks)
    data[at : at + 200] = bytes(200)
    path.write_bytes(bytes(data))
    got = read_samples(path, TOPICS, limit=100)
    for topic in TOPICS:
        stamps, values = got[topic]
        assert list(stamps) == samples[topic][0][:100]
        assert list(values) == pytest.approx(samples[topic][1][:100], rel=1e-6)  # float32
    with pytest.raises(CalibrationError, match="offset"):
        read_samples(path, TOPICS)


class _EntryPoint:
    def __init__(self, reader: Any) -> None:
        self.name, self._reader = "mcap", reader

    def load(self) -> Any:
        return self._reader


def test_the_archive_is_read_once_while_it_stays_as_it_is(tmp_path: Path, monkeypatch: Any) -> None:
    import importlib.metadata

    from modd.dataset.samples import read_samples

    reads: list[Path] = []

    def counting(path: Path, topics: list[str]) -> Any:
        reads.append(path)
        return read_samples(path, topics)

    monkeypatch.setattr(importlib.metadata, "entry_points", lambda **_: [_EntryPoint(counting)])
    path = tmp_path / "flight.mcap"
    write_archive(path, _samples(seconds=10))
    first = cli.load_calibration(str(path), TOPICS)
    again = cli.load_calibration(str(path), list(reversed(TOPICS)))
    assert len(reads) == 1 and again.series is first.series
    write_archive(path, _samples(seconds=12))  # the archive grew: read again
    grown = cli.load_calibration(str(path), TOPICS)
    assert len(reads) == 2 and len(grown.series[TOPICS[0]][0]) == 300
