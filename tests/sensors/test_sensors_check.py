"""modd-sensors reads its model through a short-lived child (modd/sensors/check.py):
the valid model comes back as the metamodel loads it, and a bad one is refused with
the metamodel's located diagnostics and exit code 1, no traceback, no reader started."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from modd.sensors.check import checked_model
from modd_model import load_model

MODEL = """
Drone usv { Sensors {
    Sensor gnss kind nmea on "/dev/null" measures { lat("deg", float64) from sentence GGA.lat; }
} }
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers { Publisher nav(0.1, "usv.gnss.lat"); }
"""


def test_the_valid_model_comes_back_as_the_metamodel_loads_it(tmp_path: Path) -> None:
    path = tmp_path / "boat.modd"
    path.write_text(MODEL)
    assert checked_model(str(path)) == load_model(path)


def test_a_bad_model_is_refused_with_located_errors(tmp_path: Path) -> None:
    path = tmp_path / "boat.modd"
    path.write_text(MODEL.replace("GGA.lat", "GGA.no_such_field"))
    run = subprocess.run(
        [str(Path(sys.executable).parent / "modd-sensors"), "--model", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 1
    assert f"{path}:3:" in run.stderr and "no_such_field" in run.stderr, run.stderr
    assert "Traceback" not in run.stderr + run.stdout
