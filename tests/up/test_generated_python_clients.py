"""The generated Python stubs work against running brokers: the integrator's
Python publisher feeds the PubBroker, and the scientist's Python subscriber
receives the scheduled values from the SubBroker."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from modd_gen import generate, write_artifacts
from modd_model import load_model


def test_generated_publisher_and_subscriber(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model_path = tmp_path / "model.modd"
    model_path.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}')
    )
    write_artifacts(tmp_path / "gen", generate(load_model(model_path)))
    zenoh = f"tcp/127.0.0.1:{free_port()}"
    run = tmp_path / "run"
    up = subprocess.Popen(
        [modd_cmd, "up", str(model_path), "--workdir", str(run), "--zenoh-listen", zenoh],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    publisher = None
    try:
        wait_for(run / "logs" / "subbroker.log", "config 1 running", 30)
        publisher = subprocess.Popen(
            [
                sys.executable,
                str(tmp_path / "gen/integrator/python/pub_1.py"),
                "--ingress",
                f"unix:{run / 'ingress.sock'}",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        sub = subprocess.run(
            [
                sys.executable,
                str(tmp_path / "gen/scientist/python/sub_5.py"),
                "--count",
                "3",
                "--credentials",
                str(run / "credentials" / "viewer.cred"),
            ],
            env={**os.environ, "MODD_ZENOH_CONNECT": zenoh},
            capture_output=True,
            text=True,
            timeout=60,
        )
    finally:
        if publisher is not None:
            publisher.send_signal(signal.SIGTERM)
            publisher.communicate(timeout=30)
        up.send_signal(signal.SIGTERM)
        up.communicate(timeout=60)
    assert sub.returncode == 0, sub.stderr
    lines = sub.stdout.strip().splitlines()
    assert len(lines) == 3
    values = [line.split(" = ")[1] for line in lines]
    assert all("usv.accelerometer.accel_z MIN" in line for line in lines)
    assert any(v != "no sample in window" and -1.0 <= float(v) <= 1.0 for v in values)
    assert publisher.returncode == 0
