"""The C++ publisher client, built as an integrator would (the example CMake project under
runtime/cpp/examples/), publishing to the real PubBroker; the archive has every sample."""

from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
from pubbroker_harness import REPO, f32, read_archive

EXAMPLE = REPO / "runtime" / "cpp" / "examples" / "publisher_example"


@pytest.fixture(scope="module")
def build(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example project, built once as an integrator would."""
    out = tmp_path_factory.mktemp("example") / "build"
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    subprocess.run(
        ["cmake", "-S", str(EXAMPLE), "-B", str(out), *gen],
        check=True,
        capture_output=True,
        timeout=120,
    )
    subprocess.run(["cmake", "--build", str(out)], check=True, capture_output=True, timeout=300)
    return out


def test_cpp_publisher_example_against_the_broker(broker_factory: Any, build: Path) -> None:
    b = broker_factory()
    for address in (f"unix:{b.unix_path}", f"tcp:127.0.0.1:{b.tcp_port}"):
        out = subprocess.run(
            [str(build / "publisher_example"), address, "100", "0"],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert out.returncode == 0, out.stdout + out.stderr
    assert b.stop() == 0
    archive = read_archive(b.archive_dir)
    for k, axis in enumerate("xyz"):
        values = [a.value for a in archive[f"usv.accelerometer.accel_{axis}"]]
        want = [f32(math.sin(0.1 * i + k)) for i in range(100)]
        assert values == want + want


def test_listing2_call_against_the_broker(broker_factory: Any, build: Path) -> None:
    """publisher->publish("accel_z", timestamp, value) with a double on a float32 topic: every
    sample archived (the Python mcap reader as oracle), a wrong name refused at the call."""
    b = broker_factory()
    out = subprocess.run(
        [str(build / "listing2"), f"unix:{b.unix_path}", "500"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "unknown topic 'accel_zz'" in out.stderr + out.stdout
    assert "usv.accelerometer.accel_z" in out.stderr  # the message says what the drone has
    assert b.stop() == 0
    values = [a.value for a in read_archive(b.archive_dir)["usv.accelerometer.accel_z"]]
    assert values == [f32(9.81 + 0.001 * i) for i in range(500)]
