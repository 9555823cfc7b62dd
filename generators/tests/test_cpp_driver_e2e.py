"""The integrator's journey: generate the driver project of a scenario, build it
with CMake alone, run it against a real PubBroker started from the generated
operator config, and find every sample in the MCAP archive."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader
from modd.ports import free_port
from modd_gen import generate, write_artifacts
from modd_model import load_model

REPO = Path(__file__).resolve().parents[2]
PUBBROKER = REPO / "build" / "bin" / "modd-pubbroker"
READINGS = 40


def _build(project: Path) -> Path:
    build = project / "build"
    subprocess.run(
        ["cmake", "-S", str(project), "-B", str(build), "-G", "Ninja"],
        check=True,
        capture_output=True,
        timeout=300,
    )
    subprocess.run(["cmake", "--build", str(build)], check=True, capture_output=True, timeout=600)
    (exe,) = [p for p in build.iterdir() if p.name.endswith("_driver")]
    return exe


def _archived(archive: Path) -> dict[str, list[float]]:
    values: dict[str, list[float]] = {}
    for f in sorted(archive.glob("*.mcap")):
        with f.open("rb") as stream:
            for _, channel, message in make_reader(stream).iter_messages():
                payload = json.loads(message.data)
                values.setdefault(channel.topic, []).append(payload["value"])
    return values


@pytest.mark.parametrize("scenario", ["scenario1", "scenario2"])
def test_generated_driver_builds_runs_and_is_archived(
    scenarios_dir: Path, tmp_path: Path, scenario: str
) -> None:
    if not PUBBROKER.is_file():
        pytest.fail(f"{PUBBROKER} is missing: run `make build` first")
    model = load_model(scenarios_dir / f"{scenario}.modd")
    write_artifacts(tmp_path / "gen", generate(model))
    exe = _build(tmp_path / "gen" / "integrator" / "pub_1-driver")

    config = json.loads((tmp_path / "gen" / "operator" / "pubbroker.json").read_text())
    config["archive"]["dir"] = str(tmp_path / "archive")
    config["ingress"]["unix_path"] = str(tmp_path / "ingress.sock")
    config["link"]["port"] = free_port()
    (tmp_path / "pubbroker.json").write_text(json.dumps(config))
    env = {**os.environ, "MODD_LINK_KEY": "a-test-link-key-of-16+"}
    broker = subprocess.Popen(
        [str(PUBBROKER), "--config", str(tmp_path / "pubbroker.json")],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
    )
    try:
        deadline = time.monotonic() + 10
        while not (tmp_path / "ingress.sock").exists():
            assert time.monotonic() < deadline, "the PubBroker did not open its ingress socket"
            assert broker.poll() is None, broker.stdout.read() if broker.stdout else ""
            time.sleep(0.05)
        run = subprocess.run(
            [str(exe), "--count", str(READINGS), "--ingress", f"unix:{tmp_path / 'ingress.sock'}"],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert run.returncode == 0, run.stderr
        assert "cannot reach" not in run.stderr, run.stderr
    finally:
        broker.send_signal(signal.SIGTERM)
        out, _ = broker.communicate(timeout=30)
    assert broker.returncode == 0, out

    archived = _archived(tmp_path / "archive")
    topics = model["publishers"][0]["topics"]
    assert sorted(archived) == sorted(topics)
    for topic in topics:
        assert len(archived[topic]) == READINGS, topic
        assert all(-1.0 <= v <= 1.0 for v in archived[topic])  # the skeleton's test signal

    # No broker at the ingress: the driver says so at once (not after its 5 s flush).
    gone = f"unix:{tmp_path / 'gone.sock'}"
    _says_unreachable_at_once([str(exe), "--count", "1", "--ingress", gone], gone)


def _says_unreachable_at_once(cmd: list[str], ingress: str) -> None:
    """Runs a driver with nothing listening at `ingress`: its first line on stderr, while it
    still runs, names the PubBroker it cannot reach; it ends (failing) once its flush gives up."""
    start = time.monotonic()
    with subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    ) as proc:
        try:
            assert proc.stderr is not None
            first = proc.stderr.readline()
            elapsed = time.monotonic() - start
            running = proc.poll() is None
            assert f"cannot reach the PubBroker at {ingress}" in first, first
            # Said while the driver still runs, before its 5 s flush gives up (startup included;
            # the machine may be loaded).
            assert running and elapsed < 4.5, f"said after {elapsed:.1f} s (running: {running})"
            proc.stderr.read()
            assert proc.wait(timeout=30) != 0
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def test_generated_python_driver_says_at_once_it_cannot_reach_the_broker(
    scenarios_dir: Path, tmp_path: Path
) -> None:
    model = load_model(scenarios_dir / "scenario1.modd")
    write_artifacts(tmp_path / "gen", generate(model))
    script = tmp_path / "gen" / "integrator" / "python" / "pub_1.py"
    ingress = f"unix:{tmp_path / 'gone.sock'}"
    _says_unreachable_at_once(
        [sys.executable, str(script), "--count", "1", "--ingress", ingress], ingress
    )
