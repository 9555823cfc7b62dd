"""The generated Python subscriber stub says which values are historical: a
backfilled window's line ends in ``(backfilled)``, a live one's does not (the
stub and its carried client run as a scientist runs them, against a router
with a SubBroker's authentication and access control)."""

from __future__ import annotations

import contextlib
import queue
import subprocess
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

from modd.ports import free_port
from modd.subbroker.payload import DeliveredValue
from modd_gen import generate, write_artifacts
from modd_model import load_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from support.loopback import shared_credentials, zenoh_router  # noqa: E402

SCENARIO = Path(__file__).resolve().parents[2] / "metamodel/examples/scenarios/scenario1.modd"


def test_the_python_stub_prints_the_historical_mark(tmp_path: Path) -> None:
    write_artifacts(tmp_path / "gen", generate(load_model(SCENARIO)))
    port = free_port()
    live = DeliveredValue(
        "sub_5", "usv.accelerometer.accel_z", "MIN", "0.25", "M", 1, 9, 2_000, 2_250, -0.5, None, 1
    )
    late = replace(live, slot=3, start_ns=750, end_ns=1_000, value=-0.25, backfilled=True)
    lines: queue.Queue[str] = queue.Queue()
    with zenoh_router(port) as station:
        stub = subprocess.Popen(
            [
                sys.executable,
                str(tmp_path / "gen/scientist/python/sub_5.py"),
                "--connect",
                f"tcp/127.0.0.1:{port}",
                "--credentials",
                str(shared_credentials().cred_file("viewer")),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        assert stub.stdout is not None
        out = stub.stdout

        def pump() -> None:
            for line in out:
                lines.put(line.rstrip("\n"))

        threading.Thread(target=pump, daemon=True).start()
        try:
            first = ""
            deadline = time.monotonic() + 30
            while not first:  # the live value again until the stub's session is subscribed
                assert time.monotonic() < deadline, stub.stderr
                station.put("modd/usv/sub/sub_5", live.to_json())
                with contextlib.suppress(queue.Empty):
                    first = lines.get(timeout=0.3)
            station.put("modd/usv/sub/sub_5", late.to_json())
            got = [first]
            while not got[-1].endswith("-0.25 (backfilled)"):
                got.append(lines.get(timeout=10))
        finally:
            stub.terminate()
            stub.communicate(timeout=10)
    assert set(got[:-1]) == {"2250 usv.accelerometer.accel_z MIN = -0.5"}
    assert got[-1] == "1000 usv.accelerometer.accel_z MIN = -0.25 (backfilled)"
