"""The scientist's generated C++ subscriber (on the C++ subscriber client)
receives its values over the SubBroker's TCP delivery, from running brokers
fed by the integrator's generated Python publisher."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from modd_gen import generate, write_artifacts
from modd_model import load_model


def _build(project: Path) -> Path:
    subprocess.run(
        ["cmake", "-S", str(project), "-B", str(project / "build"), "-G", "Ninja"],
        check=True,
        capture_output=True,
        timeout=300,
    )
    subprocess.run(
        ["cmake", "--build", str(project / "build")], check=True, capture_output=True, timeout=600
    )
    return project / "build" / "sub_5_subscriber"


def test_cpp_subscriber_gets_values_over_tcp(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    text = (scenarios_dir / "scenario1.modd").read_text()
    text = text.replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}')
    sub_port = free_port()
    text = text.replace('"127.0.0.1":7405', f'"127.0.0.1":{sub_port}')
    model_path = tmp_path / "model.modd"
    model_path.write_text(text)
    write_artifacts(tmp_path / "gen", generate(load_model(model_path)))
    exe = _build(tmp_path / "gen" / "scientist" / "cpp" / "sub_5")

    run = tmp_path / "run"
    subscriber = subprocess.Popen(
        [str(exe)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    up = subprocess.Popen(
        [
            modd_cmd,
            "up",
            str(model_path),
            "--workdir",
            str(run),
            "--zenoh-listen",
            f"tcp/127.0.0.1:{free_port()}",
        ],
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
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        time.sleep(3)  # twelve 0.25 s windows
    finally:
        for p in (publisher, up, subscriber):
            if p is not None:
                p.send_signal(signal.SIGTERM)
        if publisher is not None:
            publisher.wait(timeout=30)
        up.communicate(timeout=60)
        out, _ = subscriber.communicate(timeout=30)
    assert subscriber.returncode == 0, out
    assert f"listening on 127.0.0.1:{sub_port}" in out
    values = [line for line in out.splitlines() if "usv.accelerometer.accel_z MIN = " in line]
    assert len(values) >= 4, out
    assert all(-1.0 <= float(v.rsplit("= ", 1)[1]) <= 1.0 for v in values)
