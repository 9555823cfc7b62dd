"""The scientist's download knows where it runs: the Python subscriber of a
zip made for a deployment connects to that deployment's SubBroker endpoint
with no option, reads a viewer's credentials from the file given at run time
(the zip holds no password) and prints the values delivered; run without
credentials, it names the deployment's credentials file."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import threading
import zipfile
from pathlib import Path
from typing import Any

from modd.subbroker.payload import DeliveredValue
from modd.zenoh_auth import read_credentials
from modd_backend.downloads import role_zip, station_of
from modd_contracts.keys import sub_key
from modd_model.io import load_model

REPO = Path(__file__).resolve().parents[2]
TOPIC = "usv.accelerometer.accel_x"


def _value(i: int) -> DeliveredValue:
    return DeliveredValue(
        "sub_1",
        TOPIC,
        "AVERAGE",
        "2.0",
        "METER_PER_SECOND_SQUARED",
        1,
        i,
        i * 2_000_000_000,
        (i + 1) * 2_000_000_000,
        0.5 + i,
        50,
        10**18 + i,
    )


def _download(tmp: Path, endpoint: str, credentials_dir: Path) -> Path:
    model = load_model(REPO / "metamodel" / "examples" / "scenarios" / "scenario1.modd")
    station = station_of((endpoint,), credentials_dir / "backend.cred")
    data = role_zip(model, "scientist", "demo-r1-scientist", station)
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        z.extractall(tmp)
        text = "".join(z.read(n).decode() for n in z.namelist())
    for identity in ("viewer", "backend", "subbroker"):  # no password in the download
        assert read_credentials(credentials_dir / f"{identity}.cred").password not in text
    readme = (tmp / "demo-r1-scientist" / "scientist" / "README.md").read_text()
    assert f"`{endpoint}`" in readme and str(credentials_dir / "viewer.cred") in readme
    return tmp / "demo-r1-scientist" / "scientist" / "python" / "sub_1.py"


def _run(script: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MODD_ZENOH")}
    return subprocess.run(
        [sys.executable, str(script), *args], capture_output=True, text=True, timeout=120, env=env
    )


def test_downloaded_subscriber_receives_with_the_credentials_file(
    tmp_path: Path, router: tuple[str, Any, Any]
) -> None:
    endpoint, store, session = router
    script = _download(tmp_path, endpoint, store.dir)
    viewer = store.cred_file("viewer")

    refused = _run(script, "--count", "1")
    assert refused.returncode == 1
    assert f"--credentials {viewer}" in refused.stderr and "needs credentials" in refused.stderr

    stop = threading.Event()

    def publish() -> None:
        i = 0
        while not stop.wait(0.1):
            session.put(sub_key("usv", "sub_1"), _value(i).to_json())
            i += 1

    feeder = threading.Thread(target=publish, daemon=True)
    feeder.start()
    try:
        got = _run(script, "--credentials", str(viewer), "--count", "3")
    finally:
        stop.set()
        feeder.join(5)
    assert got.returncode == 0, got.stderr
    lines = got.stdout.splitlines()
    assert len(lines) == 3 and all(f" {TOPIC} AVERAGE = " in line for line in lines), lines
    for line in lines:  # each line is a value that was put: end_ns and value agree
        end_ns, value = int(line.split()[0]), float(line.rsplit("= ", 1)[1])
        i = end_ns // 2_000_000_000 - 1
        assert value == 0.5 + i, line
