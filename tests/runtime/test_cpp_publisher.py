"""The C++ publisher client, built as an integrator would (the example CMake project under
runtime/cpp/examples/), publishing to the real PubBroker; the archive has every sample."""

from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path
from typing import Any

from pubbroker_harness import REPO, f32, read_archive

EXAMPLE = REPO / "runtime" / "cpp" / "examples" / "publisher_example"


def test_cpp_publisher_example_against_the_broker(broker_factory: Any, tmp_path: Path) -> None:
    build = tmp_path / "build"
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    subprocess.run(["cmake", "-S", str(EXAMPLE), "-B", str(build), *gen], check=True,
                   capture_output=True, timeout=120)
    subprocess.run(["cmake", "--build", str(build)], check=True, capture_output=True, timeout=300)
    b = broker_factory()
    for address in (f"unix:{b.unix_path}", f"tcp:127.0.0.1:{b.tcp_port}"):
        out = subprocess.run([str(build / "publisher_example"), address, "100", "0"],
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stdout + out.stderr
    assert b.stop() == 0
    archive = read_archive(b.archive_dir)
    for k, axis in enumerate("xyz"):
        values = [a.value for a in archive[f"usv.accelerometer.accel_{axis}"]]
        want = [f32(math.sin(0.1 * i + k)) for i in range(100)]
        assert values == want + want
